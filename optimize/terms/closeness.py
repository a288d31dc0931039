"""Closeness to the reference surface: the tangent-plane term.

The paper's ``f_close`` is the tangent-plane approximation
``sum_i ((v_i - y_i) . n_i)^2`` with footpoints ``y_i`` on the reference and
unit normals ``n_i`` there, recomputed every iteration so that vertices may
slide along the surface.  The normal at a footpoint interpolates the
(area-weighted) vertex normals, so it is continuous: a vertex lying on an
edge or a vertex of the reference gets the same tangent plane whichever
neighbouring triangle the search reports (and the optimizer stays invariant
under rigid motions).
Footpoints come from :mod:`optimize.proximity` (exact).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..proximity.surface import Reference


def closeness_residual(V: np.ndarray, Y: np.ndarray, N: np.ndarray) -> np.ndarray:
    """(n,) float: ``r_i = (v_i - y_i) . n_i`` for vertices, footpoints and unit normals ``(n, 3)``
    (in the units of ``V``; the paper's methods divide by their mean edge length)."""
    return np.einsum("ij,ij->i", V - Y, N)


def closeness_terms(V: np.ndarray, ref: Reference, Y: np.ndarray | None = None,
                    N: np.ndarray | None = None) -> tuple[sp.csr_matrix, np.ndarray]:
    """Tangent-plane closeness ``((v_i - y_i) . n_i)^2`` linearized at ``V``.

    V : (n, 3) float vertices (or the stacked ``(3n,)`` vector).
    ref : Reference.  ``Y, N (n, 3)`` footpoints and normals, computed from
        ``ref`` when not given.
    Returns ``J (n, 3n)`` sparse with ``J[i, 3 i + k] = n_i[k]`` and the
    residual ``r (n,)``, ``r_i = (v_i - y_i) . n_i``; the energy is ``|r|^2``
    and ``r + J dx`` its linearization (exact: the residual is linear in ``V``
    for fixed footpoints).
    """
    V = np.asarray(V, dtype=np.float64).reshape(-1, 3)
    if Y is None or N is None:
        Y, N = ref.closest(V)
    n = len(V)
    r = closeness_residual(V, Y, N)
    rows = np.repeat(np.arange(n), 3)
    cols = np.arange(3 * n)
    J = sp.csr_matrix((N.ravel(), (rows, cols)), shape=(n, 3 * n))
    return J, r
