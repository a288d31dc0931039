"""Fairness: second differences along the mesh polylines (paper ``f_fair``).

Rows and columns of the mesh continue straight through regular interior
valence-4 vertices and along the boundary through boundary vertices with two
faces (``topology.fair_triples``); squares that would reach across the
boundary are dropped.  ``f_fair(V) = |K x|^2`` with ``x = V.ravel()``.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh


def fairness_matrix(mesh: Mesh) -> sp.csr_matrix:
    """(3t, 3n) sparse: ``(K x)[3 i + k] = a_k - 2 v_k + b_k`` for triple ``i = (a, v, b)``.

    ``x = V.ravel()`` is the stacked vertex vector (vertex ``j``, coordinate
    ``k`` at ``3 j + k``); ``t = len(mesh.topology.fair_triples)``.  The
    matrix is unweighted and in the units of ``V``: callers scale it (the
    optimizer divides by the mean edge length).
    """
    T = mesh.topology.fair_triples  # (t, 3)
    t, n = len(T), mesh.n_vertices
    rows = (3 * np.arange(t)[:, None, None] + np.arange(3)[None, None, :])  # (t, 1, 3)
    rows = np.broadcast_to(rows, (t, 3, 3))
    cols = 3 * T[:, :, None] + np.arange(3)[None, None, :]  # (t, 3, 3): triple slot, coordinate
    vals = np.broadcast_to(np.array([1.0, -2.0, 1.0])[None, :, None], (t, 3, 3))
    return sp.csr_matrix((vals.ravel(), (rows.ravel(), cols.ravel())), shape=(3 * t, 3 * n))


def fairness_matrix_parts(mesh: Mesh) -> tuple[sp.csr_matrix, sp.csr_matrix]:
    """The two halves ``K1 = a - v`` and ``K2 = b - v`` of :func:`fairness_matrix` (``K = K1 + K2``).

    Each half couples only the two ends of one edge: the optimizer uses
    ``2 (K1^T K1 + K2^T K2) >= K^T K`` as a fill-free majorant.
    """
    T = mesh.topology.fair_triples
    t, n = len(T), mesh.n_vertices
    rows = np.broadcast_to(3 * np.arange(t)[:, None, None] + np.arange(3)[None, None, :], (t, 2, 3))
    vals = np.broadcast_to(np.array([1.0, -1.0])[None, :, None], (t, 2, 3))
    out = []
    for end in (0, 2):
        cols = 3 * T[:, [end, 1], None] + np.arange(3)[None, None, :]
        out.append(sp.csr_matrix((vals.ravel(), (rows.ravel(), cols.ravel())), shape=(3 * t, 3 * n)))
    return out[0], out[1]


def fairness_energy(mesh: Mesh, V: np.ndarray | None = None) -> float:
    """``|K x|^2 / h^2`` with ``h`` the mean edge length: scale-free fairness energy."""
    V = mesh.V if V is None else V
    T = mesh.topology.fair_triples
    d = V[T[:, 0]] - 2 * V[T[:, 1]] + V[T[:, 2]]
    e = mesh.topology.edges
    h = np.linalg.norm(V[e[:, 1]] - V[e[:, 0]], axis=1).mean()
    return float(np.einsum("ij,ij->", d, d) / h ** 2)


def roughness(mesh: Mesh, V: np.ndarray | None = None) -> float:
    """Mean second difference ``|a - 2 v + b|`` along the mesh polylines over the mean edge
    length (scale-free; 0 for straight, evenly spaced lines): the fairness figure of reports."""
    V = mesh.V if V is None else V
    T = mesh.topology.fair_triples
    if not len(T):
        return 0.0
    d = V[T[:, 0]] - 2 * V[T[:, 1]] + V[T[:, 2]]
    e = mesh.topology.edges
    h = np.linalg.norm(V[e[:, 1]] - V[e[:, 0]], axis=1).mean()
    return float(np.linalg.norm(d, axis=1).mean() / max(h, 1e-300))
