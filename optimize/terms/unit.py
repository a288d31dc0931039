"""Unit length of auxiliary vectors: ``u . u - 1 = 0`` for every row of a ``(k, 3)`` block."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .variables import Layout


def terms(x: np.ndarray, layout: Layout, name: str) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual ``(k,)`` and Jacobian ``(k, layout.size)`` for block ``name`` of width 3."""
    U = layout.view(x, name)
    r = np.einsum("ij,ij->i", U, U) - 1.0
    k = len(U)
    J = sp.csr_matrix(((2.0 * U).ravel(), (np.repeat(np.arange(k), 3), layout.index(name).ravel())),
                      shape=(k, layout.size))
    return r, J
