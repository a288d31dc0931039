"""Congruence rows: the corner distances of a face pulled to its class's shape.

Two planar polygons are congruent (one may be the other's mirror image) exactly
when the distances between corresponding corners agree, every pair of corners
(a quad: four edges and two diagonals).  A face of a class of faces to be made
congruent (:mod:`optimize.solvers.rationalize`) has its corners listed in the
order that matches the class's first face (``corners (q, k)``: a cyclic shift,
reversed for the other hand); its rows are

    r[f, (i, j)] = |v_{corners[f, i]} - v_{corners[f, j]}| - target[f, (i, j)]

for every pair ``i < j`` (:func:`pairs`), the targets the class's mean of the
same distances, fixed while the rows act (the rationalization renews them).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .variables import Layout


def pairs(k: int) -> np.ndarray:
    """(k (k - 1) / 2, 2) int: the corner pairs ``i < j`` of a ``k``-gon (edges and diagonals)."""
    i, j = np.triu_indices(k, 1)
    return np.stack([i, j], axis=1)


def distances(V: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(q, P) float: the corner distances of faces ``corners (q, k)`` at positions ``V (n, 3)``, in the
    order of :func:`pairs`."""
    pr = pairs(corners.shape[1])
    return np.linalg.norm(V[corners[:, pr[:, 0]]] - V[corners[:, pr[:, 1]]], axis=2)


def terms(x: np.ndarray, layout: Layout, corners: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual ``(q P,)`` and Jacobian ``(q P, layout.size)`` of the congruence rows.

    corners : (q, k) int vertex indices of each face in its class's corner order.
    target : (q, P) float distances (same units as ``x``), :func:`pairs` order.
    """
    V = layout.view(x, "vertices")
    pr = pairs(corners.shape[1])
    a, b = corners[:, pr[:, 0]].ravel(), corners[:, pr[:, 1]].ravel()          # (q P,)
    d = V[a] - V[b]
    length = np.linalg.norm(d, axis=1)
    r = length - np.asarray(target, dtype=float).ravel()
    u = d / np.maximum(length, 1e-300)[:, None]
    idx = layout.index("vertices")
    rows = np.repeat(np.arange(len(a)), 6)
    cols = np.concatenate([idx[a], idx[b]], axis=1).ravel()
    vals = np.concatenate([u, -u], axis=1).ravel()
    return r, sp.csr_matrix((vals, (rows, cols)), shape=(len(a), layout.size))
