"""Edge-length floor: an edge may not get shorter than a given length (a one-sided row).

With boundary gliding a boundary vertex may slide along the curve; nothing
else stops it from sliding onto its neighbour or into a fixed corner, which
turns a quad into a triangle with a zero-length edge (planar and conical
rows are then easy to meet, and the panel cannot be built).  The row of edge
``(a, b)`` is the hinge ``min(0, |v_a - v_b| - floor)``: zero while the edge is
long enough, so it only acts on edges about to collapse, and its square is
continuously differentiable.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .variables import Layout


def terms(x: np.ndarray, layout: Layout, edges: np.ndarray, floor: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual ``(e,)`` and Jacobian ``(e, layout.size)`` of the hinge rows.

    edges : (e, 2) int vertex pairs; floor : (e,) float lengths (same units as ``x``).
    Rows of edges at or above their floor are zero, with a zero Jacobian row.
    """
    V = layout.view(x, "vertices")
    d = V[edges[:, 0]] - V[edges[:, 1]]
    length = np.linalg.norm(d, axis=1)
    short = length < floor
    r = np.where(short, length - floor, 0.0)
    k = np.nonzero(short)[0]  # entries for the acting rows only
    u = d[k] / np.maximum(length[k], 1e-300)[:, None]
    idx = layout.index("vertices")
    rows = np.repeat(k, 6)
    cols = np.concatenate([idx[edges[k, 0]], idx[edges[k, 1]]], axis=1).ravel()
    vals = np.concatenate([u, -u], axis=1).ravel()
    J = sp.csr_matrix((vals, (rows, cols)), shape=(len(edges), layout.size))
    return r, J


def shortfall(V: np.ndarray, edges: np.ndarray, floor: np.ndarray) -> np.ndarray:
    """(e,) float: how much shorter than its floor each edge is (0 when long enough); ``V (n, 3)``."""
    return np.maximum(floor - np.linalg.norm(V[edges[:, 0]] - V[edges[:, 1]], axis=1), 0.0)
