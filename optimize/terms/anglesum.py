"""Opposite angles of circular quads: ``phi1 + phi3 - pi = 0`` and ``phi2 + phi4 - pi = 0``.

The centre formulation (``constraints.circular``) also holds for four points
on a circle taken in a crossing order (a bow-tie); these rows rule that branch
out, so the circular target uses both.  Block: ``vertices (n, 3)``.  Rows
``2 i``, ``2 i + 1`` for quad ``i`` (faces with ``face_sizes == 4``, in order).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from .angles import angle_rows
from .variables import Layout


def terms(x: np.ndarray, layout: Layout, mesh: Mesh) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual ``(2q,)`` and Jacobian ``(2q, layout.size)``."""
    t = mesh.topology
    Q = np.nonzero(mesh.face_sizes == 4)[0]
    C = t.offsets[Q][:, None] + np.arange(4)[None, :]  # (q, 4) corners in face order
    pairs = np.concatenate([C[:, [0, 2]], C[:, [1, 3]]], axis=0)  # (2q, 2): quad-major below
    order = np.stack([np.arange(len(Q)), len(Q) + np.arange(len(Q))], axis=1).ravel()
    return angle_rows(x, layout, mesh, pairs[order], np.ones(2), np.full(2 * len(Q), np.pi))
