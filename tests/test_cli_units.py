"""``--units`` of the standalone commands, offsets past the focal distance, triangle input refused."""
from __future__ import annotations

import json

import numpy as np
import pytest

from fabricate.app.cli import main
from fabricate.app.cli.units import UNIT_TO_MM, UNITS
from fabricate.app.config import UNIT_TO_MM as CONFIG_UNITS
from fabricate.offset import offset_structure
from fabricate.offset.turnover import area_quadratic, focal_limits, turned_faces
from optimize.modelling import shapes
from optimize.mesh.io import read_mesh, write_mesh
from optimize.mesh import Mesh

RADIUS_M, RISE_M = 8.0, 3.0
SPHERE_M = (RADIUS_M ** 2 + RISE_M ** 2) / (2 * RISE_M)  # the dome is a cap of this sphere


def _dome(scale: float = 1.0) -> Mesh:
    m = shapes.revolution(shapes.dome_profile(radius=RADIUS_M, rise=RISE_M, k=6), 12, name="dome")
    return m.with_vertices(m.V * scale)


@pytest.fixture
def dome_m(tmp_path):
    """A conical dome written in metres (8 m span)."""
    path = tmp_path / "dome_m.obj"
    write_mesh(path, _dome())
    return path


def test_units_are_the_configs():
    assert UNIT_TO_MM == CONFIG_UNITS and set(UNITS) == set(CONFIG_UNITS)


def test_faces_turn_over_at_the_sphere_radius():
    """On a spherical cap every node axis passes through the centre: the layer collapses there."""
    mesh = _dome(1000.0)
    s = offset_structure(mesh, (0.0, -100.0))
    coef = area_quadratic(mesh, s.normals, s.offset)
    lo, hi, f_lo, f_hi = focal_limits(coef)
    R = SPHERE_M * 1000.0
    inward = lo if np.isfinite(lo) else -hi  # whichever side the normals point away from
    assert -R <= inward <= -0.8 * R
    side = np.sign(inward)
    assert turned_faces(coef, 0.5 * side * R).size == 0
    assert turned_faces(coef, 1.1 * side * R).size == mesh.n_faces
    assert s.report["turned_over"]["ok"]


def test_offset_in_metres_read_as_mm_turns_faces_over_loudly(dome_m, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["offset", str(dome_m), "--distances=0,-200,200", "-o", str(out)]) == 3
    stdout = capsys.readouterr().out
    assert "FACES TURN OVER" in stdout
    rep = json.loads((out / "offset_report.json").read_text())
    t = rep["turned_over"]
    assert not t["ok"] and t["count"] > 0
    bad = [L for L in t["per_layer"] if L["count"]]
    assert bad and all(L["faces"] for L in bad)
    assert f"faces {', '.join(map(str, bad[0]['faces'][:3]))}" in stdout  # ids printed, first few
    assert rep["input"]["units"] == "mm"


def test_offset_with_units_m_is_clean_and_in_mm(dome_m, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["offset", str(dome_m), "--distances=0,-200", "-o", str(out), "--units", "m"]) == 0
    stdout = capsys.readouterr().out
    assert "TURN OVER" not in stdout and "file in m" in stdout
    rep = json.loads((out / "offset_report.json").read_text())
    assert rep["turned_over"]["ok"] and rep["input"]["mm_per_unit"] == 1000.0
    assert rep["mesh"]["bbox_diagonal_mm"] == pytest.approx(_dome(1000.0).bbox_diagonal())
    layer = read_mesh(out / "layer_0.obj")
    assert np.allclose(layer.V, _dome(1000.0).V)  # output files in mm
    assert rep["face_distance"]["per_layer"][1]["max_error_mm"] < 1e-6  # conical: exact at 200 mm


def test_measure_reports_lengths_in_mm(dome_m, capsys):
    assert main(["measure", str(dome_m), "--units", "m"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert main(["measure", str(dome_m)]) == 0
    t = json.loads(capsys.readouterr().out)
    assert s["units"]["lengths"] == "mm" and s["units"]["file"] == "m"
    assert s["edge_length"]["mean"] == pytest.approx(1000.0 * t["edge_length"]["mean"])
    assert s["planarity"]["max"] == pytest.approx(t["planarity"]["max"], abs=1e-12)  # scale-free


def test_optimize_writes_in_the_files_unit(tmp_path, capsys):
    noisy = shapes.perturbed(_dome(), 0.01, seed=3)
    src = tmp_path / "noisy_m.obj"
    write_mesh(src, noisy)
    out = tmp_path / "opt_m.obj"
    code = main(["optimize", str(src), "-o", str(out), "--units", "m", "--progress", "off"])
    assert code in (0, 3)
    stdout = capsys.readouterr().out
    assert " mm of " in stdout  # the distance to the reference in mm
    res = read_mesh(out)
    assert np.abs(res.V - noisy.V).max() < 0.05 * RADIUS_M  # metres in, metres out
    assert np.abs(res.V).max() == pytest.approx(np.abs(noisy.V).max(), rel=0.05)


def test_shapes_writes_in_the_asked_unit(tmp_path, capsys):
    assert main(["shapes"]) == 0
    name = capsys.readouterr().out.split(":")[0].strip()
    a, b = tmp_path / "a_mm.obj", tmp_path / "a_m.obj"
    assert main(["shapes", name, "-o", str(a)]) == 0
    assert main(["shapes", name, "-o", str(b), "--units", "m"]) == 0
    assert "units m" in capsys.readouterr().out
    assert np.allclose(read_mesh(a).V, 1000.0 * read_mesh(b).V)


def _triangles(tmp_path) -> str:
    m = _dome(1000.0)
    path = tmp_path / "tri.obj"
    write_mesh(path, Mesh(m.V, m.triangulate(), name="tri"))
    return str(path)


@pytest.mark.parametrize("target", ["pq", "conical"])
def test_optimize_refuses_a_triangle_mesh_at_once(tmp_path, capsys, target):
    src = _triangles(tmp_path)
    out = tmp_path / "out.obj"
    assert main(["optimize", src, "-o", str(out), "--target", target]) == 2
    err = capsys.readouterr().err
    assert "faces are triangles" in err and "fabricate remesh" in err and "input.surface" in err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists()


def test_run_input_stage_refuses_a_triangle_mesh(tmp_path):
    from fabricate.app.quads import RUN_HINT, require_quads
    from optimize.errors import MeshError

    m = read_mesh(_triangles(tmp_path))
    with pytest.raises(MeshError, match="input.surface"):
        require_quads(m, "input.mesh tri.obj", hint=RUN_HINT)
    require_quads(_dome(), "input.mesh dome.obj", hint=RUN_HINT)  # quads pass


def test_run_with_a_triangle_mesh_exits_2_before_optimizing(tmp_path, capsys):
    import yaml

    src = _triangles(tmp_path)
    cfg = tmp_path / "tri.yaml"
    cfg.write_text(yaml.safe_dump({"name": "tri", "input": {"mesh": src}, "subdivision": {"levels": 0}}))
    code = main(["run", str(cfg), "--out", str(tmp_path / "outputs"), "-q"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "faces are triangles" in err and "input.surface" in err
    assert not (tmp_path / "outputs" / "tri").exists()


def test_optimize_prints_the_worst_defect_it_stops_on(tmp_path, capsys):
    """The message's 'worst defect/tolerance 10^x' is one of the printed maxima."""
    import re

    src = tmp_path / "noisy.obj"
    write_mesh(src, shapes.perturbed(_dome(1000.0), 0.05, seed=1))
    assert main(["optimize", str(src), "-o", str(tmp_path / "o.obj"), "--target", "conical",
                 "--max-iter", "1", "--progress", "off"]) == 3
    out = capsys.readouterr().out
    score = float(re.search(r"worst defect/tolerance 10\^(-?[\d.]+)", out).group(1))
    maxima = [float(x) for x in re.findall(r"max (\S+)  mean", out)]
    assert any(abs(np.log10(v / 1e-6) - score) < 0.01 for v in maxima if v > 0), (score, maxima)


def test_remesh_notes_count_the_faces_written(tmp_path, capsys):
    """The seamless branch collapses boundary slivers after tracing: the note counts what is written."""
    import re

    from optimize.remesh import surfaces

    f = (lambda x, y: 0.1 * (x ** 3 - 3 * x * y * y),
         lambda x, y: 0.1 * np.stack([3 * x * x - 3 * y * y, -6 * x * y], 1),
         lambda x, y: 0.1 * np.stack([np.stack([6 * x, -6 * y], 1), np.stack([-6 * y, -6 * x], 1)], 1))
    surf = surfaces.height_field(f, size=(3.0, 3.0), n=(41, 41))
    src, out = tmp_path / "saddle.obj", tmp_path / "quads.obj"
    write_mesh(src, surf.mesh.with_vertices(surf.mesh.V * 1000.0))  # mm
    assert main(["remesh", str(src), "--edge-length", "300", "-o", str(out), "--optimize", "none",
                 "--side=" + ",".join(map(str, surf.side))]) == 0
    stdout = capsys.readouterr().out
    written = read_mesh(out)
    counted = [tuple(map(int, m)) for m in re.findall(r"(\d+) quads, (\d+) other faces", stdout)]
    assert counted, stdout
    q = int(np.sum(written.face_sizes == 4))
    assert all(c == (q, written.n_faces - q) for c in counted), (counted, q, written.n_faces)


def test_run_with_a_layer_past_the_focal_distance_is_marked_and_builds_no_parts(tmp_path):
    """The offset stage's turned-over faces stop the CAD stage with the reason and exit 3."""
    import sys

    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    from _pipeline_fixtures import tiny_config

    from fabricate.app.pipeline import run_pipeline

    cfg = tiny_config(tmp_path, offset={"distances": [0, -9000]})
    s = run_pipeline(cfg, tmp_path / "out")
    assert s.exit_code == 3 and "offset_turned_over" in s.message and "FACES TURN OVER" in s.message
    rep = json.loads((__import__("pathlib").Path(s.out_dir) / "report.json").read_text())
    m = rep["measures"]["offset_turned_over"]
    assert m["pass"] is False and m["enforced"] and m["max"] > 0 and m["worst"]
    lo, hi = m["safe_range_mm"]
    assert -9000 < lo < 0
    assert rep["parts"] is None and "FACES TURN OVER" in " ".join(rep["offset"]["summary"])


def test_a_too_deep_beam_says_to_reduce_the_depth(tmp_path):
    """9 m deep beams under a cap of a 12 m sphere: the advice is the depth, not the beam width."""
    from fabricate.cad import PartError, PartSpec, build_parts

    s = offset_structure(_dome(1000.0), (0.0, -9000.0))
    assert s.report["turned_over"]["ok"]  # not past the focal distance: the beams fold at their ends
    with pytest.raises(PartError, match="reduce parts.beam_depth") as err:
        build_parts(s, PartSpec(beam_depth=9000.0, beam_width=200.0))
    assert "beam_width" not in str(err.value)


def test_optimize_shows_progress_on_stderr_when_asked(tmp_path, capsys):
    src = tmp_path / "noisy.obj"
    write_mesh(src, shapes.perturbed(_dome(1000.0), 0.05, seed=1))
    main(["optimize", str(src), "-o", str(tmp_path / "o.obj"), "--target", "conical", "--max-iter", "3",
          "--progress", "on"])
    cap = capsys.readouterr()
    assert "3/3" in cap.err and "iteration 3: planarity" in cap.err and "iteration 3:" not in cap.out
    main(["optimize", str(src), "-o", str(tmp_path / "p.obj"), "--max-iter", "3"])  # auto: not a terminal
    assert capsys.readouterr().err == ""
