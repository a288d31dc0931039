"""Closest points on the boundary polylines of a mesh (for boundary gliding).

Closest points are exact: a k-d tree over segment midpoints with the bound
``|p - m_s| <= dist(p, s) + L/2`` (``L`` the longest segment).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..errors import MeshError
from ..mesh import Mesh


def closest_on_segments(P: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """(k, 3) float: closest point to ``P[i]`` on segment ``A[i] B[i]``; inputs (k, 3)."""
    d = B - A
    dd = np.einsum("ij,ij->i", d, d)
    s = np.clip(np.einsum("ij,ij->i", P - A, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    return A + s[:, None] * d


class BoundaryCurve:
    """The boundary polylines of ``mesh`` (``(s, 2)`` segments) for closest-point queries."""

    def __init__(self, mesh: Mesh, k: int = 6):
        t = mesh.topology
        seg = t.edges[t.is_boundary_edge]
        if len(seg) == 0:
            raise MeshError(f"{mesh.name}: boundary gliding asked for, but the mesh has no boundary")
        self.A, self.B = mesh.V[seg[:, 0]], mesh.V[seg[:, 1]]
        d = self.B - self.A
        self.tangents = d / np.linalg.norm(d, axis=1, keepdims=True)
        self.half = 0.5 * float(np.linalg.norm(d, axis=1).max())
        self.tree = cKDTree(0.5 * (self.A + self.B))
        self.k = int(min(k, len(seg)))
        self.scale = mesh.bbox_diagonal()

    def closest(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Footpoints ``Y (k, 3)`` on the curve and unit tangents ``T (k, 3)`` there; ``P (k, 3)``."""
        q = len(P)
        dist_m, idx = self.tree.query(P, k=self.k)
        idx, dist_m = idx.reshape(q, self.k), dist_m.reshape(q, self.k)
        Pk = np.repeat(P, self.k, axis=0)
        Y = closest_on_segments(Pk, self.A[idx.ravel()], self.B[idx.ravel()])
        d = np.linalg.norm(Y - Pk, axis=1).reshape(q, self.k)
        best = np.argmin(d, axis=1)
        rows = np.arange(q)
        seg = idx[rows, best]
        Yb = Y.reshape(q, self.k, 3)[rows, best]
        dbest = d[rows, best]
        unsure = np.nonzero((self.k < len(self.A)) & (dist_m[:, -1] < dbest + self.half))[0]
        for i in unsure:  # rare: far points or very uneven segments
            cand = np.asarray(self.tree.query_ball_point(P[i], (dbest[i] + self.half) * (1 + 1e-9)
                                                         + 1e-12 * self.scale), dtype=np.int64)
            Yc = closest_on_segments(np.broadcast_to(P[i], (len(cand), 3)), self.A[cand], self.B[cand])
            j = int(np.argmin(np.linalg.norm(Yc - P[i], axis=1)))
            seg[i], Yb[i] = cand[j], Yc[j]
        return Yb, self.tangents[seg]
