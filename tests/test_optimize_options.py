"""OptimizeOptions: the one place the optimizer's defaults live, checked on construction."""
import dataclasses
import inspect
import os
import subprocess
import sys
from pathlib import Path

import pytest

from optimize.modelling import shapes
from optimize.api import optimize_mesh
from optimize.errors import ConfigError
from optimize.mesh.io import write_mesh
from optimize.options import DEFAULTS, LINEAR_SOLVERS, OptimizeOptions


def _defaults_of(fn) -> dict:
    return {k: p.default for k, p in inspect.signature(fn).parameters.items() if p.default is not p.empty}


@pytest.mark.parametrize("where", ["api", "run_paper_method", "penalty", "sqp", "hybrid", "Problem"])
def test_every_entry_point_takes_its_defaults_from_the_options(where):
    from optimize.solvers.paper import hybrid, penalty, problem, sqp

    fn = {"api": optimize_mesh, "run_paper_method": hybrid.run_paper_method, "penalty": penalty.penalty,
          "sqp": sqp.sqp, "hybrid": hybrid.hybrid, "Problem": problem.Problem}[where]
    got = _defaults_of(fn)
    for key in ("fairness", "closeness", "max_iter", "target", "method", "linear_solver", "formulation",
                "convex", "glide_boundary", "torsion_free_beams"):
        if key in got and not (where != "api" and key in ("target", "method")):
            assert got[key] == getattr(DEFAULTS, key), (where, key, got[key])
    assert got.get("fairness", DEFAULTS.fairness) == 1e-3 and got.get("closeness", DEFAULTS.closeness) == 1e-2


@pytest.mark.parametrize("changes,key", [({"fairness": -1.0}, "fairness"), ({"closeness": float("nan")}, "closeness"),
                                         ({"max_iter": -1}, "max_iter"), ({"max_iter": 2.5}, "max_iter"),
                                         ({"target": "flat"}, "target"), ({"method": "newton"}, "method"),
                                         ({"linear_solver": "cholespy"}, "linear_solver"),
                                         ({"formulation": "normals"}, "formulation"),
                                         ({"torsion_free_beams": "yes"}, "torsion_free_beams"),
                                         ({"convex": 1}, "convex"), ({"tol": 1e-6}, "tol"),
                                         ({"paper": {"mu": 1.0}}, "paper's methods"),
                                         ({"target": "strip"}, "paper's methods only"),
                                         ({"method": "sqp", "linear_solver": "superlu"}, "default method")])
def test_bad_values_name_the_key(changes, key):
    with pytest.raises(ConfigError, match=key):
        OptimizeOptions(**changes)


def test_options_are_frozen_and_replace_checks_again():
    opts = OptimizeOptions(target="conical", max_iter=50)
    with pytest.raises(dataclasses.FrozenInstanceError):
        opts.fairness = 0.5
    assert opts.replace(fairness=0.5).fairness == 0.5 and opts.fairness == DEFAULTS.fairness
    with pytest.raises(ConfigError, match="fairness"):
        opts.replace(fairness=-0.5)
    with pytest.raises(TypeError):
        opts.paper["mu"] = 1.0  # read-only mapping
    assert opts.as_dict()["tol"]["planarity"] == opts.tol.planarity


def test_cholespy_is_not_offered():
    assert "cholespy" not in LINEAR_SOLVERS
    with pytest.raises(ConfigError, match="linear_solver"):
        optimize_mesh(shapes.grid(3, 3), linear_solver="cholespy")


def test_explicit_pardiso_without_mkl_is_a_config_error(monkeypatch):
    from optimize.linalg import pardiso

    monkeypatch.setattr(pardiso, "available", lambda: False)
    monkeypatch.setattr(pardiso, "_LIB_ERROR", "mkl_rt not found (test)")
    mesh = shapes.perturbed(shapes.grid(4, 4), 0.05, seed=3)
    with pytest.raises(ConfigError, match="linear_solver: 'pardiso' needs Intel MKL.*mkl_rt not found"):
        optimize_mesh(mesh, linear_solver="pardiso")
    assert optimize_mesh(mesh, linear_solver="auto").status == "converged"  # auto falls back to SuperLU


def test_cli_pardiso_without_mkl_exits_2_with_one_line(tmp_path):
    path = tmp_path / "in.obj"
    write_mesh(path, shapes.perturbed(shapes.grid(4, 4), 0.05, seed=3))
    code = ("import sys\nfrom optimize.linalg import pardiso\n"
            "pardiso.available = lambda: False\n"
            "from fabricate.app.cli import main\n"
            f"sys.exit(main(['optimize', {str(path)!r}, '-o', {str(tmp_path / 'out.obj')!r}, "
            "'--linear-solver', 'pardiso']))")
    repo = str(Path(__file__).resolve().parents[1])
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([repo, os.environ.get("PYTHONPATH", "")]))
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env)
    assert p.returncode == 2, p.stderr
    lines = [ln for ln in p.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "pardiso" in lines[0] and "Traceback" not in p.stderr, p.stderr
    assert not (tmp_path / "out.obj").exists()


def test_modelling_and_remeshing_receive_the_optimizer():
    from test_layers import _imported

    from optimize.modelling.hierarchy import subdivide_and_perturb

    calls = []

    def spy(mesh, target, **kw):
        calls.append((mesh.n_faces, target, kw["max_iter"]))
        return optimize_mesh(mesh, target, **kw)

    control = shapes.perturbed(shapes.grid(4, 4, height=lambda x, y: 0.2 * x * x + 0.1 * y * y), 0.02, seed=4)
    hier = subdivide_and_perturb(control, 1, target="pq", optimizer=spy, max_iter=30)
    assert calls == [(36, "pq", 30)] and hier.levels[-1].result.success
    # and the optimizer never imports them back: they sit above the api (tests/test_optimize_layers.py orders them)
    root = Path(__file__).resolve().parents[1] / "optimize"
    below = [p for p in root.rglob("*.py") if p.relative_to(root).parts[0] not in ("modelling", "remesh")]
    back = [str(p.relative_to(root)) for p in below
            if any(name.startswith(("optimize.modelling", "optimize.remesh")) for name in _imported(p))]
    assert back == []


def test_raise_for_status_raises_convergence_error_naming_the_defects():
    from optimize.errors import ConvergenceError

    mesh = shapes.perturbed(shapes.revolution(shapes.dome_profile(k=5), 10), 0.2, seed=2)
    res = optimize_mesh(mesh, "conical", max_iter=1)
    assert res.status == "max_iter"
    with pytest.raises(ConvergenceError, match=r"default/conical ended max_iter after 1 iteration.*conical \S+ > 1e-06"):
        res.raise_for_status()
    assert ConvergenceError.exit_code == 3
    ok = optimize_mesh(shapes.perturbed(shapes.grid(4, 4), 0.02, seed=3), "pq")
    assert ok.raise_for_status() is ok


def test_every_defect_a_solver_stops_on_has_one_tolerance():
    from optimize.tolerances import HELD_TO, Tolerances

    tol = Tolerances(planarity=2e-6, conical=3e-6)
    assert tol.for_defect("planarity") == 2e-6 and tol.for_defect("circular") == tol.circular
    assert {k: tol.for_defect(k) for k in HELD_TO} == {"det": 2e-6, "glide": 2e-6, "short_edge": 2e-6,
                                                       "node_cone": 3e-6, "beam": 3e-6}
    with pytest.raises(ValueError, match="'flatness' has no tolerance"):
        tol.for_defect("flatness")
