"""Sparse Cholesky of SPD systems with Intel MKL PARDISO, symbolic analysis reused.

PARDISO (in the ``mkl`` wheel's ``mkl_rt`` library, x86-64 only) orders by
METIS nested dissection, factors with supernodal BLAS-3 kernels on every
core, and separates the three phases: analysis (ordering, symbolic
factorization) once per sparsity pattern, numeric factorization per matrix,
triangular solves per right-hand side.  The Gauss-Newton systems keep their
pattern from one iteration to the next, so only the numeric phase repeats.

Measured on the first conical system of a 10,000-face dome (99,900 unknowns,
shared 2-core machine): analysis 0.22 s, numeric factorization 0.63 s, solve
0.06 s, where SciPy's SuperLU (MMD ordering, symmetric mode) took 5.7 s for
the same factor-and-solve; PQ (60,300 unknowns) 0.06 + 0.05 + 0.015 s
against 0.35 s (``benchmarks/bench_optimize.py --linalg``).

The wrapper speaks to ``pardiso`` through ctypes, as MKL documents it; it
holds the matrix arrays it handed over for as long as the factor lives, and
releases PARDISO's memory when the factor is closed or collected.
"""
from __future__ import annotations

import ctypes
import glob
import os
import sys
import time
from ctypes.util import find_library

import numpy as np
import scipy.sparse as sp

_LIB = None
_LIB_ERROR = ""
SMALL = 20000
"""Systems with fewer unknowns are analysed on one thread."""
SMALL_FACTOR = 1_000_000
"""Factors with fewer nonzeros (known after the analysis) are computed on one thread."""

ERRORS = {-1: "input inconsistent", -2: "not enough memory", -3: "reordering problem",
          -4: "zero pivot (matrix not positive definite)", -5: "unclassified internal error",
          -6: "reordering failed", -7: "diagonal matrix is singular", -8: "32-bit integer overflow",
          -9: "not enough memory for out-of-core", -10: "error opening out-of-core files",
          -11: "read/write error with out-of-core files"}


def _load():
    """The ``mkl_rt`` library, or None (the reason in ``_LIB_ERROR``)."""
    global _LIB, _LIB_ERROR
    if _LIB is not None or _LIB_ERROR:
        return _LIB
    candidates = [os.environ.get("CONICAL_FAB_MKL_RT"), find_library("mkl_rt")]
    for root in {sys.prefix, sys.base_prefix}:
        candidates += sorted(glob.glob(os.path.join(root, "lib", "libmkl_rt.so*")), key=len)
    for path in filter(None, candidates):
        try:
            lib = ctypes.CDLL(path)
            fn = lib.pardiso
        except (OSError, AttributeError):
            continue
        fn.restype = None
        i32 = ctypes.POINTER(ctypes.c_int32)
        fn.argtypes = [ctypes.POINTER(ctypes.c_int64), i32, i32, i32, i32, i32, ctypes.c_void_p,
                       i32, i32, i32, i32, i32, i32, ctypes.c_void_p, ctypes.c_void_p, i32]
        try:
            lib.MKL_Set_Num_Threads_Local.restype = ctypes.c_int
            lib.MKL_Set_Num_Threads_Local.argtypes = [ctypes.c_int]
        except AttributeError:  # an older MKL: threads stay as MKL sets them
            pass
        _LIB = lib
        return _LIB
    _LIB_ERROR = ("Intel MKL (mkl_rt) was not found: install the 'mkl' package (x86-64), "
                  "or choose linear_solver='superlu'")
    return None


def load_error() -> str:
    """Why MKL did not load ("" when it did or was not tried yet)."""
    return _LIB_ERROR


def available() -> bool:
    """True when MKL PARDISO can be loaded here."""
    return _load() is not None


def _ptr(a: np.ndarray, ctype):
    return a.ctypes.data_as(ctypes.POINTER(ctype))


class PardisoCholesky:
    """Factor of SPD ``A`` (upper triangle used); ``update(A)`` refactors a new matrix,
    redoing the analysis only when its sparsity pattern has entries outside the analysed
    one (a matrix with fewer entries is factored in the analysed pattern, its missing
    entries stored as zeros: the convexity hinge rows of the guided solver come and go).

    Raises ``RuntimeError`` (with PARDISO's error text) when a phase fails.
    """

    def __init__(self, single: bool = False):
        lib = _load()
        if lib is None:
            raise RuntimeError(_LIB_ERROR)
        self._fn = lib.pardiso
        self.pt = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        p = self.iparm
        p[0] = 1    # iparm set here, not defaults
        p[1] = 2    # METIS nested-dissection ordering
        p[7] = 0    # iterative refinement: none (SPD, accurate enough; the caller checks)
        p[9] = 13   # pivot perturbation 1e-13 (unused for SPD)
        p[17] = -1  # report nonzeros of the factor
        p[34] = 1   # zero-based indices
        p[27] = int(single)  # the factor in single precision (half the memory; solves in float32)
        self.n = 0
        self.threads = 0  # 0: MKL's default (every core); 1 for small factors, see update
        self.analyses = 0
        self.embedded = 0  # matrices factored in the analysed pattern, a superset of theirs
        self.seconds = {"analysis": 0.0, "numeric": 0.0, "solve": 0.0}
        self._pattern = None
        self._arrays = None
        self._source = None  # the matrix self._arrays holds the upper triangle of (see update)
        self._shift = 0.0
        self._diagonal = self._diagonal0 = None
        self._factored = False

    @property
    def single(self) -> bool:
        """The factor is computed and stored in single precision (``iparm[27]``): a solve is
        then accurate to about ``1e-7`` times the condition number, and callers refine it
        (:class:`optimize.linalg.normal.NormalSolver` runs CG in double with it)."""
        return bool(self.iparm[27])

    @property
    def factor_nnz(self) -> int:
        """Nonzeros of the Cholesky factor (after a factorization)."""
        return int(self.iparm[17])

    def _call(self, phase: int, b: np.ndarray | None = None) -> np.ndarray | None:
        setter = getattr(_LIB, "MKL_Set_Num_Threads_Local", None)
        before = setter(self.threads) if setter is not None else None
        try:
            return self._call_pardiso(phase, b)
        finally:
            if setter is not None:
                setter(before)

    def _call_pardiso(self, phase: int, b: np.ndarray | None) -> np.ndarray | None:
        a, ia, ja = self._arrays if self._arrays is not None else (  # phase -1 needs no matrix
            np.zeros(1), np.zeros(2, dtype=np.int32), np.zeros(1, dtype=np.int32))
        one = np.ones(1, dtype=np.int32)
        args = [np.array([v], dtype=np.int32) for v in (1, 1, 2, phase, self.n)]
        perm = np.zeros(max(self.n, 1), dtype=np.int32)
        msglvl = np.zeros(1, dtype=np.int32)
        err = np.zeros(1, dtype=np.int32)
        dtype = np.float32 if self.single else np.float64  # the factor's precision (iparm[27])
        rhs = np.zeros(max(self.n, 1), dtype) if b is None else np.ascontiguousarray(b, dtype=dtype)
        x = np.zeros_like(rhs)
        i32 = ctypes.c_int32
        self._fn(_ptr(self.pt, ctypes.c_int64), _ptr(args[0], i32), _ptr(args[1], i32),
                 _ptr(args[2], i32), _ptr(args[3], i32), _ptr(args[4], i32), a.ctypes.data,
                 _ptr(ia, i32), _ptr(ja, i32), _ptr(perm, i32), _ptr(one, i32), _ptr(self.iparm, i32),
                 _ptr(msglvl, i32), rhs.ctypes.data, x.ctypes.data, _ptr(err, i32))
        if err[0] != 0:
            raise RuntimeError(f"PARDISO phase {phase} failed with error {int(err[0])}: "
                               f"{ERRORS.get(int(err[0]), 'unknown error')}")
        return x.astype(np.float64, copy=False) if b is not None else None

    def update(self, A: sp.spmatrix, shift: float = 0.0) -> "PardisoCholesky":
        """Factor ``A + shift I`` (``A (n, n)`` symmetric; its upper triangle is read).

        The upper triangle of ``A`` is extracted once and kept: the same ``A`` object passed
        again (a new damping ``shift`` in one Gauss-Newton iteration) only changes the kept
        diagonal in place, so ``A`` must not be modified in place between such calls."""
        if A is not self._source:
            self._source = None
            self._arrays = None  # the previous matrix's copy freed before the next is made
            data, indptr, indices = upper_triangle(A)
            if self._pattern is not None and len(indptr) == len(self._pattern[0]) and not (
                    np.array_equal(self._pattern[0], indptr) and np.array_equal(self._pattern[1], indices)):
                pos = _positions_in(self._pattern, indptr, indices)
                if pos is not None:  # fewer entries than the analysed pattern (rows that come and
                    # go, exact zeros a sparse product dropped): its values in that pattern
                    full = np.zeros(len(self._pattern[1]))
                    full[pos] = data
                    data, (indptr, indices) = full, self._pattern
                    self.embedded += 1
            self._diagonal = indptr[:-1]  # upper_triangle stores every diagonal entry first in its row
            self._diagonal0 = data[self._diagonal]  # the diagonal before any shift
            if self.single:
                data = data.astype(np.float32)
            self._arrays, self._source, self._shift = (data, indptr, indices), A, 0.0
        data, indptr, indices = self._arrays
        n = len(indptr) - 1
        if shift != self._shift:
            data[self._diagonal] = self._diagonal0 + shift
            self._shift = shift
        same = self._pattern is not None and self.n == n and (
            (self._pattern[0] is indptr and self._pattern[1] is indices)
            or (np.array_equal(self._pattern[0], indptr) and np.array_equal(self._pattern[1], indices)))
        self.n = n
        t0 = time.perf_counter()
        if not same:
            if self._factored:
                self._release()
            self.threads = 1 if n < SMALL else 0
            self._call(11)
            self.analyses += 1
            # Small factors take a few ms, where the OpenMP threads' start-up and (on a
            # shared machine) waiting for a busy core cost more than they save: on a 900-face
            # PQ run (factor 0.3M nonzeros) with the other core loaded, 1 thread spent 0.18 s
            # solving against 0.58 s with 2; at 10k faces (3.6M and more) 2 threads win.
            # Every phase of one analysis must run on the same number of threads (a numeric
            # phase on fewer threads than its analysis crashed MKL 2026.2), so a changed
            # choice is analysed again.
            wanted = 1 if self.factor_nnz < SMALL_FACTOR else 0
            if wanted != self.threads:
                self._release_handle()
                self.threads = wanted
                self._call(11)
                self.analyses += 1
            self._pattern = (indptr, indices)
        t1 = time.perf_counter()
        self._call(22)
        self._factored = True
        self.seconds["analysis"] += t1 - t0
        self.seconds["numeric"] += time.perf_counter() - t1
        return self

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``x (n,)`` with ``A x = b (n,)`` for the last factored ``A``."""
        if not self._factored:
            raise RuntimeError("PARDISO: solve before any factorization")
        b = np.asarray(b, dtype=np.float64)
        if b.shape != (self.n,):
            raise ValueError(f"PARDISO solve: right-hand side of shape {b.shape}, expected ({self.n},)")
        t0 = time.perf_counter()
        x = self._call(33, b)
        self.seconds["solve"] += time.perf_counter() - t0
        return x

    __call__ = solve

    def _release(self):
        self._release_handle()
        self._factored = False
        self._pattern = None

    def _release_handle(self):
        """Free PARDISO's memory for this handle (on the threads it was analysed with)."""
        if np.any(self.pt):
            try:
                self._call(-1)
            except RuntimeError:
                pass
        self.pt[:] = 0

    def close(self):
        """Free PARDISO's memory (the object can factor again afterwards)."""
        self._release()

    def __del__(self):
        try:
            self._release()
        except Exception:  # interpreter shutdown: nothing left to free safely
            pass


def upper_triangle(A: sp.spmatrix) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The upper triangle of a square ``A (n, n)`` as PARDISO reads it: ``(data float64,
    indptr int32, indices int32)`` in CSR, column indices sorted, duplicates summed and the
    diagonal entry stored (zero if absent) first in every row.

    Made from ``A``'s CSR arrays with one boolean mask (SciPy's ``triu`` goes through COO
    with 64-bit indices: 3x the memory of the matrix at a million faces).  A CSR ``A`` not in
    canonical form (a sparse product's unsorted indices) is put in it in place: same matrix."""
    A = A if sp.issparse(A) and A.format == "csr" else sp.csr_matrix(A)
    n = A.shape[0]
    if A.shape != (n, n) or n == 0:
        raise ValueError(f"PARDISO needs a non-empty square matrix, got shape {A.shape}")
    if not A.has_canonical_format:
        A.sum_duplicates()  # sorts the indices too
    counts = np.diff(A.indptr)
    keep = A.indices >= np.repeat(np.arange(n, dtype=A.indices.dtype), counts)
    indptr = np.zeros(n + 1, dtype=np.int64)
    if A.nnz:  # kept entries per row (a row without entries: reduceat would give its next entry)
        per_row = np.add.reduceat(keep, np.minimum(A.indptr[:-1], A.nnz - 1), dtype=np.int64)
        np.cumsum(np.where(counts > 0, per_row, 0), out=indptr[1:])
    data = A.data[keep].astype(np.float64, copy=False)
    indices = A.indices[keep].astype(np.int32, copy=False)
    del keep
    nonempty = indptr[1:] > indptr[:-1]
    if np.all(nonempty) and np.array_equal(indices[indptr[:-1]], np.arange(n, dtype=np.int32)):
        return data, indptr.astype(np.int32), indices
    U = _with_diagonal(sp.csr_matrix((data, indices, indptr), shape=(n, n)))
    return U.data.astype(np.float64), U.indptr.astype(np.int32), U.indices.astype(np.int32)


def _positions_in(pattern: tuple[np.ndarray, np.ndarray], indptr: np.ndarray,
                  indices: np.ndarray) -> np.ndarray | None:
    """Where the entries of the CSR pattern ``(indptr, indices)`` sit in ``pattern`` (both
    sorted in each row, same number of rows), or None when one of them is not in it."""
    P_indptr, P_indices = pattern
    if len(indices) > len(P_indices):
        return None
    n = len(indptr) - 1
    keys_p = np.repeat(np.arange(n, dtype=np.int64) * n, np.diff(P_indptr)) + P_indices
    keys = np.repeat(np.arange(n, dtype=np.int64) * n, np.diff(indptr)) + indices
    pos = np.minimum(np.searchsorted(keys_p, keys), len(keys_p) - 1)
    return pos if np.array_equal(keys_p[pos], keys) else None


def _with_diagonal(U: sp.csr_matrix) -> sp.csr_matrix:
    """``U`` with an explicitly stored (possibly zero) diagonal entry in every row."""
    n = U.shape[0]
    coo = U.tocoo()
    rows = np.concatenate([coo.row, np.arange(n)])
    cols = np.concatenate([coo.col, np.arange(n)])
    vals = np.concatenate([coo.data, np.zeros(n)])
    out = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
    out.sort_indices()
    return out
