"""SciPy's SuperLU with the options every caller uses: the one place they are chosen.

Symmetric matrices (normal equations, quasi-definite KKT systems): symmetric
mode, ``MMD_AT_PLUS_A`` ordering, no off-diagonal pivoting
(``diag_pivot_thresh=0``); general matrices: ``COLAMD`` with partial pivoting.
"""
from __future__ import annotations

import scipy.sparse as sp
import scipy.sparse.linalg as sla


def superlu(M: sp.spmatrix, symmetric: bool = True) -> sla.SuperLU:
    """The SuperLU factorization of a square sparse ``M (k, k)``; ``.solve(b)`` gives ``M^{-1} b``.

    Raises RuntimeError when ``M`` is singular to working precision (SciPy's error)."""
    if symmetric:
        return sla.splu(sp.csc_matrix(M), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                        options=dict(SymmetricMode=True))
    return sla.splu(sp.csc_matrix(M), permc_spec="COLAMD", diag_pivot_thresh=1.0)
