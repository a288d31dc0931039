"""Opposite angles of circular quads: ``phi1 + phi3 - pi = 0`` and ``phi2 + phi4 - pi = 0``.

The centre formulation (``terms.circular``) also holds for four points
on a circle taken in a crossing order (a bow-tie); these rows rule that branch
out, so the circular target uses both.  Block: ``vertices (n, 3)``.  Rows
``2 i``, ``2 i + 1`` for quad ``i`` (faces with ``face_sizes == 4``, in order).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from .angles import angle_rows, rows_at
from .variables import Layout


def rows(mesh: Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows as corner sets: ``C (2q, 2)`` (rows ``2 i``: corners 0, 2 of quad ``i``;
    ``2 i + 1``: corners 1, 3), signs ``(2,)`` and offsets ``(2q,)`` (pi); row ``i`` is
    ``sum_s signs[s] angle(C[i, s]) - offset[i]`` (both methods build on this)."""
    base = mesh.topology.offsets[np.nonzero(mesh.face_sizes == 4)[0]]
    C = np.stack([base, base + 2, base + 1, base + 3], axis=1).reshape(-1, 2)  # quad-major
    return C, np.ones(2), np.full(len(C), np.pi)


def terms(x: np.ndarray, layout: Layout, mesh: Mesh) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual ``(2q,)`` and Jacobian ``(2q, layout.size)``."""
    return angle_rows(x, layout, mesh, *rows(mesh))


def at_positions(mesh: Mesh, V: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
    """The rows at positions ``V (n, 3)``, ``(phi1 + phi3 - pi, phi2 + phi4 - pi)`` per quad: residual ``(p,)`` and
    Jacobian ``(p, 3 n)`` with columns ``x = V.ravel()`` (the unknowns are the vertices alone)."""
    return rows_at(mesh, V, *rows(mesh))
