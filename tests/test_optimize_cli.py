"""``fabricate optimize``: writes OUT with the same faces, prints the measures, exit 3 when the
tolerance is not reached (OUT and the report still written and saying so)."""
import json

import numpy as np

from fabricate.app.cli import main
from optimize.mesh import measures
from optimize.modelling import shapes
from optimize.mesh.io import read_mesh, write_mesh


def _noisy(tmp_path):
    mesh = shapes.perturbed(shapes.revolution(shapes.dome_profile(k=6), 12), 0.05, seed=21)
    path = tmp_path / "in.obj"
    write_mesh(path, mesh)
    return mesh, path


def test_optimize_conical_writes_mesh_and_report(tmp_path, capsys):
    mesh, path = _noisy(tmp_path)
    out, rep = tmp_path / "out.off", tmp_path / "report.json"
    code = main(["optimize", str(path), "-o", str(out), "--target", "conical", "--report", str(rep)])
    assert code == 0
    res = read_mesh(out)
    np.testing.assert_array_equal(res.F, mesh.F)
    assert measures.planarity(res).max() <= 1e-6 and measures.conical_defect(res).max() <= 1e-6
    report = json.loads(rep.read_text())
    assert report["success"] is True and report["tolerance_reached"] is True
    assert report["history"] and "conical" in report["history"][-1]
    text = capsys.readouterr().out
    assert "converged" in text and "conical" in text


def test_optimize_formulation_and_solver_flags(tmp_path, capsys):
    mesh, path = _noisy(tmp_path)
    out = tmp_path / "out.obj"
    code = main(["optimize", str(path), "-o", str(out), "--target", "conical",
                 "--formulation", "auxiliary", "--linear-solver", "superlu"])
    assert code == 0
    assert measures.conical_defect(read_mesh(out)).max() <= 1e-6
    assert "converged" in capsys.readouterr().out


def test_optimize_exit_3_when_budget_too_small(tmp_path, capsys):
    _, path = _noisy(tmp_path)
    out, rep = tmp_path / "out.obj", tmp_path / "r.json"
    code = main(["optimize", str(path), "-o", str(out), "--target", "circular", "--max-iter", "1",
                 "--report", str(rep)])
    assert code == 3
    assert out.exists()
    assert "# NOT CONVERGED: circular max_iter after 1 iterations" in out.read_text().splitlines()[1]
    report = json.loads(rep.read_text())
    assert report["success"] is False and report["status"] == "max_iter"
    assert "NOT reached" in capsys.readouterr().out


def test_optimize_bad_input_exit_2(tmp_path, capsys):
    _, path = _noisy(tmp_path)
    assert main(["optimize", str(path), "-o", str(tmp_path / "o.obj"), "--fix", "edges"]) == 2
    assert main(["optimize", str(path), "-o", str(tmp_path / "o.obj"), "--tol", "-1"]) == 2
    assert "error:" in capsys.readouterr().err
