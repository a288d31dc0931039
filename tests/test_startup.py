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


def _loaded_after(code: str) -> set[str]:
    """Top-level packages of ``HEAVY`` in ``sys.modules`` after running ``code`` in a fresh interpreter."""
    probe = (f"import sys\n{code}\n"
             f"import json; print(json.dumps(sorted({{m.split('.')[0] for m in sys.modules}} & {set(HEAVY)!r})))")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(REPO), os.environ.get("PYTHONPATH", "")]))
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, timeout=120,
                         check=True).stdout
    return set(json.loads(out.strip().splitlines()[-1]))


def test_import_errors_loads_nothing_heavy():
    assert _loaded_after("import optimize.errors") == set()


def test_fabricate_help_loads_nothing_heavy():
    code = ("import contextlib, io\nfrom fabricate.app.cli import main\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    try:\n        main(['--help'])\n    except SystemExit:\n        pass")
    assert _loaded_after(code) == set()


def test_measure_loads_nothing_heavy(cylinder_path):
    code = ("import contextlib, io\nfrom fabricate.app.cli import main\n"
            f"with contextlib.redirect_stdout(io.StringIO()):\n    assert main(['measure', {str(cylinder_path)!r}]) == 0")
    assert _loaded_after(code) == set()  # components in NumPy (optimize.components)


@pytest.mark.parametrize("name", ["optimize_mesh", "Mesh", "MeshError", "Tolerances", "OptimizeResult"])
def test_lazy_names_still_import(name):
    import optimize

    assert getattr(optimize, name) is getattr(__import__("optimize", fromlist=[name]), name)
    assert name in dir(optimize)
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        optimize.not_a_name  # noqa: B018
