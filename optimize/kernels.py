"""Compiled per-iteration kernels of the paper's methods (numba), used when numba is installed.

An iteration of penalty or SQP on the 336-quad trefoil band is a few hundred
microseconds of arithmetic spread over some hundred NumPy calls; the calls'
overhead, not the arithmetic, dominated.  These kernels do the same
arithmetic in one compiled call each:

- :func:`angles` and :func:`dets`: corner angles ``(c,)`` with gradients
  ``(c, 9)`` and the four strip determinants ``(q, 4)`` with gradients
  ``(q, 4, 12)``, the formulas of :func:`optimize.mesh.corners.angle_local`
  and :func:`optimize.terms.determinants.det_local`;
- :func:`closest_candidates`: the closest point among each query point's
  candidate triangles (:class:`optimize.proximity.Footpoints`), the
  case analysis of :func:`optimize.proximity.surface.closest_on_triangles`;
- :func:`scan_triangles`: new candidates for points that moved, every
  triangle tested (box, then exact distance);
- :func:`interpolated_normals`: ``optimize.proximity.surface.Reference._interpolated_normals``;
- :func:`quad_planarity_max`: the largest of ``optimize.mesh.measures.quad_planarity``;
- :func:`scatter_rows`: a term's Jacobian values summed into CSR data;
- :func:`csr_matvec`: ``M @ x`` for CSR ``M`` (:func:`matvec` falls back to SciPy);
- :func:`group_gram`: the Gram entries of groups of CSR rows with equal
  columns, summed into the band of :class:`optimize.solvers.paper.assembly.GramBand`;
- :func:`ldl_factor`, :func:`ldl_solve`: ``L D L^T`` of a symmetric band
  without pivoting: the penalty method's positive definite normal equations
  (in place of LAPACK's banded Cholesky, a little faster and without the
  wrappers' copies), and, tried first, SQP's quasi-definite KKT matrix (a
  quarter of the work of the banded LU with partial pivoting, which remains
  the fallback when a solution fails the accuracy checks).

Every kernel loops over elements (the compiled counterpart of a vectorized
expression: STYLE's rule 3 is about Python loops).  Without numba, with the
environment variable ``CONICAL_FAB_NUMBA=0``, or with ``ENABLED = False``
(tests switch it off to check the fallback), :func:`get` returns None and
the callers keep their NumPy code.  numba is imported on
first use, not with the package; kernels are compiled on first call and
cached on disk (``cache=True``) outside the package folder: in ``NUMBA_CACHE_DIR`` when set, else
in the user's cache folder (``$XDG_CACHE_HOME`` or ``~/.cache``, then ``conical-fab/numba``;
:func:`cache_dir`), so an installed package's folder is never written to; :func:`warm_up` compiles them all and
returns the seconds it took, for benchmarks to report apart from the runs.
"""
from __future__ import annotations

import contextlib
import os
import threading
import time

import numpy as np

ENABLED = os.environ.get("CONICAL_FAB_NUMBA", "1") != "0"  # False: the NumPy paths
_KERNELS = None  # module namespace once compiled, False when numba is missing
_THREAD = threading.local()  # .off: within disabled() in this thread


def _on() -> bool:
    return ENABLED and not getattr(_THREAD, "off", False)


def get():
    """The compiled kernels (an object with the functions below as attributes), or None."""
    global _KERNELS
    if not _on():
        return None
    if _KERNELS is None:
        if not _import_numba():
            _KERNELS = False
        else:
            from . import _numba_kernels
            _KERNELS = _numba_kernels
    return _KERNELS or None


def cache_dir() -> str | None:
    """Where the compiled kernels are cached: ``NUMBA_CACHE_DIR`` when the user set it, else
    ``conical-fab/numba`` in the user's cache folder, made here; None when it cannot be made (numba
    then chooses, as it does without this)."""
    given = os.environ.get("NUMBA_CACHE_DIR")
    if given:
        return given
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    path = os.path.join(base, "conical-fab", "numba")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:
        return None
    return path


def _import_numba() -> bool:
    """Import numba with its cache outside the package folder (:func:`cache_dir`); False without it."""
    path = cache_dir()
    if path and not os.environ.get("NUMBA_CACHE_DIR"):
        os.environ["NUMBA_CACHE_DIR"] = path  # read by numba's config when it is imported
    try:
        import numba
    except ImportError:
        return False
    if path and not numba.config.CACHE_DIR:  # numba was imported before this (by the caller): set it there
        numba.config.CACHE_DIR = path
    return True


_LOADED: dict = {}  # module name -> the module, or False when it did not import (no numba)


def load(module: str):
    """Another compiled kernel module (``fabricate.export._nest_kernel`` ...), imported on first use, or None
    without numba or when the kernels are switched off (:data:`ENABLED`, ``CONICAL_FAB_NUMBA=0``: one switch
    for the optimizer's kernels and every other)."""
    if not _on():
        return None
    if module not in _LOADED:
        import importlib

        try:
            _LOADED[module] = _import_numba() and importlib.import_module(module)
        except ImportError:
            _LOADED[module] = False
    return _LOADED[module] or None


def matvec(M, x: np.ndarray) -> np.ndarray:
    """``M @ x`` for a CSR matrix ``M (r, k)`` and ``x (k,)`` float: compiled when the kernels
    exist (SciPy's call overhead is most of the cost on the small matrices of an iteration)."""
    k = get()
    if k is None or M.format != "csr" or x.dtype != np.float64 or M.dtype != np.float64:
        return M @ x
    return k.csr_matvec(M.indptr, M.indices, M.data, np.ascontiguousarray(x))


@contextlib.contextmanager
def disabled():
    """Within the block, in this thread, :func:`get` and :func:`load` return None (the NumPy paths);
    other threads (a batch's jobs on one Dask worker) keep the kernels."""
    was, _THREAD.off = getattr(_THREAD, "off", False), True
    try:
        yield
    finally:
        _THREAD.off = was


def warm_up() -> float:
    """Compile (or load from the disk cache) every kernel on a tiny input; seconds taken (0 without numba)."""
    t0 = time.perf_counter()
    k = get()
    if k is None:
        return 0.0
    V = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0.1], [0, 1, 0]])
    vid = np.array([[0, 1, 3], [1, 2, 0], [2, 3, 1], [3, 0, 2]], dtype=np.int64)
    k.angles(V, vid, True)
    k.angles(V, vid, False)
    q = np.array([[0, 1, 2, 3]], dtype=np.int64)
    k.dets(V, q, True)
    k.dets(V, q, False)
    k.quad_planarity_max(V, q)
    tri = np.array([[0, 1, 2]], dtype=np.int64)
    A, B, C = V[tri[:, 0]], V[tri[:, 1]], V[tri[:, 2]]
    one = np.zeros(1, dtype=np.int64)
    k.scan_triangles(V, np.zeros(1, np.int64), np.zeros(1, np.int64), 0.1, 0.0, A, B, C, A, A)
    Y, t, _ = k.closest_candidates(V[:1], A, B, C, one * 0, one * 0, np.zeros(1, dtype=np.bool_), A, A, one * 0)
    k.interpolated_normals(Y, t, A, B, C, tri, V[:3] * 0 + [0.0, 0, 1], np.array([[0.0, 0, 1]]))
    Lb = np.array([[2.0, 1.0], [3.0, 0.0]])
    ext = np.array([1, 0], np.int64)
    k.ldl_factor(Lb, True, ext)
    Lb = np.array([[2.0, 1.0], [3.0, 0.0]])
    k.ldl_factor(Lb, False, ext)
    k.ldl_solve(Lb, np.ones(2), ext)
    out = np.zeros(2)
    k.csr_matvec(np.array([0, 1], np.int32), np.array([0], np.int32), np.ones(1), np.ones(1))
    k.scatter_rows(out, np.zeros((1, 1), np.int64), np.ones(1), np.ones((1, 1)), np.zeros(1, np.int64))
    z, one = np.zeros(1, np.int64), np.ones(1, np.int64)
    k.group_gram(np.ones(2), np.zeros((1, 1), np.int64), 1, z, z, one.reshape(1, 1), out)
    return time.perf_counter() - t0
