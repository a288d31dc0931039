"""#33 item 5: the compiled kernels are cached outside the package folder (the user's cache folder, or
NUMBA_CACHE_DIR when set), so an installed package is never written to."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("numba")
REPO = Path(__file__).resolve().parents[1]
CODE = ("import numpy as np, numba; from optimize import kernels; k = kernels.get(); "
        "import optimize._numba_kernels as m; print(numba.config.CACHE_DIR); "
        "from fabricate.export.nesting import _kernel; print(bool(_kernel()))")


def _run(tmp_path, **env):
    full = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "XDG_CACHE_HOME")}
    full.update(env, PYTHONPATH=str(REPO))
    p = subprocess.run([sys.executable, "-c", CODE], capture_output=True, text=True, timeout=300, env=full,
                       cwd=tmp_path)
    assert p.returncode == 0, p.stderr[-2000:]
    return p.stdout.split()


def test_the_kernel_cache_is_in_the_users_cache_folder(tmp_path):
    where, _ = _run(tmp_path, XDG_CACHE_HOME=str(tmp_path / "cache"))
    assert Path(where) == tmp_path / "cache" / "conical-fab" / "numba"
    assert REPO not in Path(where).parents


def test_numba_cache_dir_given_by_the_user_wins(tmp_path):
    where, _ = _run(tmp_path, XDG_CACHE_HOME=str(tmp_path / "cache"), NUMBA_CACHE_DIR=str(tmp_path / "mine"))
    assert Path(where) == tmp_path / "mine" and not (tmp_path / "cache" / "conical-fab").exists()
