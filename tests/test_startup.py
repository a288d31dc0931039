"""Light imports stay light: the command line and the error classes start without SciPy,
matplotlib, numba or the CAD kernel (package ``__init__`` files re-export lazily, PEP 562).
Timings are in benchmarks/bench_startup.py; here only what gets imported."""
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
HEAVY = ("scipy", "matplotlib", "numba", "OCP", "build123d", "ifcopenshell", "rhino3dm", "openseespy")


def _loaded_after(code: str, watch=HEAVY) -> set[str]:
    """Packages of ``watch`` in ``sys.modules`` after running ``code`` in a fresh interpreter
    (a dotted name counts when it or one of its submodules is loaded)."""
    probe = (f"import sys\n{code}\n"
             f"loaded = {{p for m in sys.modules for p in {tuple(watch)!r} if m == p or m.startswith(p + '.')}}\n"
             "import json; print(json.dumps(sorted(loaded)))")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]))
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, timeout=120,
                         check=True).stdout
    return set(json.loads(out.strip().splitlines()[-1]))


def test_import_errors_loads_nothing_heavy():
    assert _loaded_after("import optimize.errors") == set()


@pytest.mark.parametrize("target", ["pq", "conical"])
def test_default_run_loads_neither_the_paper_stack_nor_numba(target):
    """An ordinary run (default method, closeness on) imports no ``optimize.solvers.paper``, numba,
    matplotlib or CAD kernel: checked in ``sys.modules`` of a fresh interpreter, so an eager
    import anywhere on the path would show."""
    code = ("from optimize import optimize_mesh\n"
            "from optimize.modelling import shapes\n"
            "m = shapes.perturbed(shapes.grid(4, 4, height=lambda u, v: 0.3 * u * v), 0.02, seed=1)\n"
            f"res = optimize_mesh(m, {target!r})\n"
            "assert res.nit > 0, res.message")
    assert _loaded_after(code, HEAVY + ("optimize.solvers.paper",)) == {"scipy"}


def test_fabricate_help_loads_nothing_heavy():
    code = ("import contextlib, io\nfrom fabricate.app.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    try:\n        main(['--help'])\n    except SystemExit:\n        pass")
    assert _loaded_after(code) == set()


def test_measure_loads_nothing_heavy(cylinder_path):
    code = ("import contextlib, io\nfrom fabricate.app.cli import main\n"
            f"with contextlib.redirect_stdout(io.StringIO()):\n    assert main(['measure', {str(cylinder_path)!r}]) == 0")
    assert _loaded_after(code) == set()  # components in NumPy (optimize.mesh.components)


@pytest.mark.parametrize("name", ["optimize_mesh", "Mesh", "MeshError", "Tolerances", "OptimizeResult"])
def test_lazy_names_still_import(name):
    import optimize

    assert getattr(optimize, name) is getattr(__import__("optimize", fromlist=[name]), name)
    assert name in dir(optimize)
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        optimize.not_a_name  # noqa: B018
