"""Subdivision of polylines as sparse operators: Chaikin and Lane-Riesenfeld.

``P : (n, d) float`` is a polyline (any dimension ``d``); a closed polyline
does not repeat its first point.  Each function returns the refined polyline
and ``S : (n_fine, n)`` scipy CSR with ``P_fine = S @ P`` (rows sum to one).

Lane-Riesenfeld of degree ``d``: double every point, then average neighbours
``d`` times; the limit is the uniform B-spline of degree ``d`` (``d = 2`` is
Chaikin's corner cutting, ``d = 3`` the cubic B-spline with masks
``(1, 6, 1) / 8`` at the old points and ``(1, 1) / 2`` at the new ones).
Fine points of a closed polyline are numbered so that fine point ``2 i``
belongs to coarse point ``i`` (odd degrees: its vertex point; even degrees:
the first point on the segment ``i, i + 1``); the operator is circulant.

Open polylines keep their end points, as the boundary curves of
Catmull-Clark (``degree = 3``) and Doo-Sabin (``degree = 2``) surfaces with
corners do in :mod:`optimize.modelling.subdivision`:

- ``degree = 1``: ``2 n - 1`` points (midpoints inserted);
- ``degree = 2``: ``2 n`` points ``p_0, (3 p_0 + p_1) / 4, (p_0 + 3 p_1) / 4, ..., p_(n-1)``;
- ``degree = 3``: ``2 n - 1`` points, end points kept, ``(p_(i-1) + 6 p_i + p_(i+1)) / 8``
  inside and midpoints between.
Higher degrees are available for closed polylines only.
"""
from __future__ import annotations

from math import comb

import numpy as np
import scipy.sparse as sp

from ..errors import ConfigError

__all__ = ["chaikin", "lane_riesenfeld", "curve_operator", "refine_count", "CURVE_SCHEMES"]

CURVE_SCHEMES = {"chaikin": 2, "lane_riesenfeld": 3}
"""Scheme name -> Lane-Riesenfeld degree."""


def _check(n: int, closed: bool, degree) -> int:
    if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or degree < 1:
        raise ConfigError(f"curve subdivision degree is {degree!r}, expected an integer >= 1")
    if not closed and degree > 3:
        raise ConfigError(f"curve subdivision degree {degree} on an open polyline is not available, "
                          "expected 1, 2 or 3 (or a closed polyline)")
    need = 3 if closed else 2
    if n < need:
        raise ConfigError(f"a {'closed' if closed else 'open'} polyline has {n} point(s), "
                          f"expected at least {need}")
    return int(degree)


def refine_count(n: int, closed: bool, degree: int) -> int:
    """Number of points after one step on ``n`` points."""
    if closed:
        return 2 * n
    return 2 * n if degree == 2 else 2 * n - 1


def curve_operator(n: int, closed: bool, degree: int = 3) -> sp.csr_matrix:
    """(n_fine, n) CSR: one Lane-Riesenfeld step of ``degree`` on ``n`` points."""
    degree = _check(n, closed, degree)
    if closed:
        nf = 2 * n
        shift = (degree - 1) // 2
        j = np.arange(degree + 1)
        w = np.array([comb(degree, int(i)) for i in j], dtype=float) / 2.0 ** degree
        r = np.repeat(np.arange(nf), degree + 1)
        jj = np.tile(j, nf)
        cols = ((r - shift + jj) // 2) % n
        return sp.csr_matrix((np.tile(w, nf), (r, cols)), shape=(nf, n))
    i = np.arange(n - 1)
    if degree == 1:
        rows = np.concatenate([2 * np.arange(n), 2 * i + 1, 2 * i + 1])
        cols = np.concatenate([np.arange(n), i, i + 1])
        vals = np.concatenate([np.ones(n), np.full(2 * (n - 1), 0.5)])
        nf = 2 * n - 1
    elif degree == 2:
        rows = np.concatenate([[0, 2 * n - 1], 2 * i + 1, 2 * i + 1, 2 * i + 2, 2 * i + 2])
        cols = np.concatenate([[0, n - 1], i, i + 1, i, i + 1])
        q = np.full(n - 1, 0.25)
        vals = np.concatenate([[1.0, 1.0], 3 * q, q, q, 3 * q])
        nf = 2 * n
    else:
        k = np.arange(1, n - 1)  # interior old points
        rows = np.concatenate([[0, 2 * n - 2], 2 * i + 1, 2 * i + 1, 2 * k, 2 * k, 2 * k])
        cols = np.concatenate([[0, n - 1], i, i + 1, k - 1, k, k + 1])
        vals = np.concatenate([[1.0, 1.0], np.full(2 * (n - 1), 0.5),
                               np.full(n - 2, 0.125), np.full(n - 2, 0.75), np.full(n - 2, 0.125)])
        nf = 2 * n - 1
    return sp.csr_matrix((vals, (rows, cols)), shape=(nf, n))


def lane_riesenfeld(P, closed: bool, degree: int = 3, levels: int = 1) -> tuple[np.ndarray, sp.csr_matrix]:
    """Lane-Riesenfeld subdivision of a polyline ``P (n, d)``, ``levels`` times.

    Returns ``(P_fine (n_fine, d), S (n_fine, n) CSR)`` with ``P_fine = S @ P``.
    """
    P = np.asarray(P, dtype=float)
    if P.ndim != 2:
        raise ConfigError(f"polyline has shape {P.shape}, expected (n, d)")
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or levels < 0:
        raise ConfigError(f"curve subdivision levels is {levels!r}, expected an integer >= 0")
    S = sp.identity(len(P), format="csr")
    n = len(P)
    for _ in range(levels):
        S1 = curve_operator(n, closed, degree)
        S = (S1 @ S).tocsr()
        n = S.shape[0]
    return S @ P, S


def chaikin(P, closed: bool, levels: int = 1) -> tuple[np.ndarray, sp.csr_matrix]:
    """Chaikin's corner cutting of ``P (n, d)`` (Lane-Riesenfeld of degree 2)."""
    return lane_riesenfeld(P, closed, degree=2, levels=levels)
