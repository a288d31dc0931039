"""Sparse linear algebra of every solver: one factorization layer, its backends.

Every backend factors a square sparse matrix once per sparsity pattern's
symbolic analysis and returns solutions ``x = M^{-1} b``:

- ``normal`` (:class:`NormalSolver`): the default method's SPD normal equations;
  backends PARDISO (``pardiso``: MKL, symbolic analysis reused, numeric
  refactorization per iteration), SuperLU (``superlu``), block elimination of
  per-face unknowns, and conjugate gradients preconditioned by the last factor;
- ``spd`` (:class:`SPDSolver`, :class:`Factor`, :func:`solve`): the paper's
  methods' systems, checked (residual, conditioning) with the LSQR fallback
  for near-singular matrices; banded when a narrow band exists;
- ``banded``: one ordering per run and the band refilled per iteration
  (LAPACK banded Cholesky / LU, or the compiled ``L D L^T``).
Names load on first use (PEP 562).
"""
from .._lazy import lazy_exports

_EXPORTS = {
    "BACKENDS": ".normal", "NormalSolver": ".normal", "SolveError": ".normal",
    "normal_matrix": ".normal", "resolve_backend": ".normal", "Shifted": ".normal",
    "SPDSolver": ".spd", "Factor": ".spd", "lstsq": ".spd", "COND_LIMIT": ".spd", "RESIDUAL_TOL": ".spd",
    "superlu": ".superlu:superlu",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
