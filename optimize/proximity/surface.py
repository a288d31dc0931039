"""Exact closest points and normals on a triangulated reference surface.

The reference is a polygon mesh, fan-triangulated.  Closest points are exact:
k-d trees over the triangle centroids propose candidates and a bound proves
none was missed.  Triangles are grouped by size (centroid-to-vertex radii
within a factor 2), one tree per group.  For a query point ``p`` let ``d*``
be the exact distance to the best of its ``k`` nearest-centroid triangles
over all groups and ``R`` the largest radius in a group.  Every point ``q`` of a triangle
``T`` satisfies ``|p - c_T| <= |p - q| + R``, so a triangle closer than ``d*``
has its centroid within ``d* + R`` of ``p``.  When the group's ``k``-th
centroid is farther than that, its ``k`` candidates contain every triangle
of the group that could be closer; otherwise every centroid of the group in
the ball of radius ``d* + R`` is tested.  Point-triangle distances
use the Voronoi-region test of Ericson (Real-Time Collision Detection, 5.1.5),
vectorized over all pairs.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..mesh import Mesh
from ..tolerances import CLOSEST_TIE as TIE  # closest-point ties: the lowest triangle index wins


def closest_on_triangles(P: np.ndarray, A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
    """(k, 3) float: closest point to ``P[i]`` on triangle ``(A[i], B[i], C[i])``; all inputs (k, 3)."""
    dot = lambda x, y: np.einsum("ij,ij->i", x, y)  # noqa: E731
    ab, ac, ap = B - A, C - A, P - A
    d1, d2 = dot(ab, ap), dot(ac, ap)
    bp = P - B
    d3, d4 = dot(ab, bp), dot(ac, bp)
    cp = P - C
    d5, d6 = dot(ab, cp), dot(ac, cp)
    vc = d1 * d4 - d3 * d2
    vb = d5 * d2 - d1 * d6
    va = d3 * d6 - d5 * d4

    def ratio(num, den):
        return num / np.where(den != 0, den, 1.0)

    t_ab = ratio(d1, d1 - d3)[:, None]
    t_ac = ratio(d2, d2 - d6)[:, None]
    t_bc = ratio(d4 - d3, (d4 - d3) + (d5 - d6))[:, None]
    den = va + vb + vc
    v = ratio(vb, den)[:, None]
    w = ratio(vc, den)[:, None]
    conds = [
        (d1 <= 0) & (d2 <= 0),                          # vertex A
        (d3 >= 0) & (d4 <= d3),                         # vertex B
        (vc <= 0) & (d1 >= 0) & (d3 <= 0),              # edge AB
        (d6 >= 0) & (d5 <= d6),                         # vertex C
        (vb <= 0) & (d2 >= 0) & (d6 <= 0),              # edge AC
        (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0),  # edge BC
    ]
    choices = [A, B, A + t_ab * ab, C, A + t_ac * ac, B + t_bc * (C - B)]
    inside = A + v * ab + w * ac
    return np.select([c[:, None] for c in conds], choices, default=inside)


def _vertex_normals(mesh: Mesh, T: np.ndarray, nrm: np.ndarray):
    """Unit vertex normals ``(n, 3)``: the sums of the area-weighted triangle normals ``nrm (t, 3)``
    of the triangles ``T (t, 3)`` around each vertex; and the normals the interpolation over each
    triangle uses at its corners: rows ``(t, 3)`` of a table ``(m, 3)``.

    Where the faces around a vertex disagree on their orientation (the ends of an edge whose two
    faces run along it in the same direction: the seam of a Moebius band) the triangle normals are
    summed turned to the side of the vertex's first triangle (the lowest index); summed as they
    are they cancel (to 1e-15 of a normal at the trefoil band's seam, a direction rounding chose).
    A triangle whose corner normal at such a vertex points away from its own normal interpolates
    the opposite one (a row added to the table), so that its normals do not pass through zero.
    A consistently oriented mesh has no such vertex: the table is the vertex normals and the rows
    are ``T``.
    """
    t, n = mesh.topology, mesh.n_vertices
    c0, c1 = t.edge_corners[~t.is_boundary_edge].T
    same = t.corner_vertex[c0] == t.corner_vertex[c1]  # the two faces run the edge the same way
    seam = np.zeros(n, dtype=bool)
    seam[t.corner_vertex[c0[same]]] = seam[t.corner_next_vertex[c0[same]]] = True
    sign = np.ones(T.shape)
    if seam.any():
        first = np.full(n, len(T))
        for j in range(3):
            np.minimum.at(first, T[:, j], np.arange(len(T)))
        facing = np.einsum("tjk,tk->tj", nrm[np.minimum(first, len(T) - 1)[T]], nrm)
        sign = np.where(seam[T] & (facing < 0), -1.0, 1.0)
    vn = np.zeros((n, 3))
    for j in range(3):  # three scatter-adds, not a loop over triangles
        np.add.at(vn, T[:, j], sign[:, j, None] * nrm)
    vn /= np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-300)
    if not seam.any():
        return vn, T, vn
    away = seam[T] & (np.einsum("tjk,tk->tj", vn[T], nrm) < 0)
    extra = np.flatnonzero(seam)
    row = np.full(n, -1, dtype=np.int64)
    row[extra] = n + np.arange(len(extra))
    return vn, np.where(away, row[T], T), np.concatenate([vn, -vn[extra]])


class Reference:
    """A reference surface for closest-point queries.

    Parameters
    ----------
    mesh : Mesh
        Any polygon mesh; faces are fan-triangulated (``mesh.triangulate()``).
    k : int
        Nearest-centroid candidates tested before the exactness bound is checked.
    """

    def __init__(self, mesh: Mesh, k: int = 8):
        self.mesh = mesh
        T = mesh.triangulate()  # (t, 3)
        self.triangles = T
        sizes = mesh.face_sizes
        self.triangle_face = np.concatenate(
            [np.nonzero(sizes > j + 1)[0] for j in range(1, mesh.F.shape[1] - 1)])
        X = mesh.V[T]  # (t, 3, 3)
        self._A, self._B, self._C = X[:, 0], X[:, 1], X[:, 2]
        self.centroids = X.mean(axis=1)
        radii = np.linalg.norm(X - self.centroids[:, None, :], axis=2).max(axis=1)  # (t,)
        self.radius = float(radii.max())
        nrm = np.cross(self._B - self._A, self._C - self._A)
        length = np.linalg.norm(nrm, axis=1)
        from ..mesh.measures import face_normals

        fallback = face_normals(mesh)[self.triangle_face]
        ok = length > 1e-14 * max(self.radius, 1e-300) ** 2
        self.normals = np.where(ok[:, None], nrm / np.where(ok, length, 1.0)[:, None], fallback)
        self.vertex_normals, self.normal_corners, self.normal_table = _vertex_normals(mesh, T, nrm)
        # triangles grouped by size (radii within a factor 2), one k-d tree each, so
        # that the exactness bound uses the largest radius of the group, not of the mesh
        level = np.floor(np.log2(np.maximum(radii, 1e-300) / max(radii.min(), 1e-300))).astype(int)
        while len(np.unique(level)) > 8:
            level //= 2
        self.groups = []
        for lv in np.unique(level):  # a handful of groups
            members = np.nonzero(level == lv)[0]
            self.groups.append((members, cKDTree(self.centroids[members]), float(radii[members].max()),
                                int(min(k, len(members)))))
        self.k = int(k)
        self.bbox_diagonal = mesh.bbox_diagonal()

    def closest(self, P: np.ndarray, return_index: bool = False):
        """Closest points on the reference.

        P : (k, 3) float query points.
        Returns ``Y (k, 3)`` footpoints and ``N (k, 3)`` unit normals there
        (vertex normals interpolated over the triangle, see
        :meth:`_interpolated_normals`), and ``tri (k,)`` triangle indices
        with ``return_index``.  Footpoints are exact up to floating point.
        """
        P = np.asarray(P, dtype=np.float64).reshape(-1, 3)
        q = len(P)
        dbest = np.full(q, np.inf)
        Yb = np.zeros((q, 3))
        tri = np.zeros(q, dtype=np.int64)
        kth = []
        for members, tree, _, k in self.groups:  # the k nearest centroids of every group
            dist_c, idx = tree.query(P, k=k)
            dist_c, idx = dist_c.reshape(q, k), members[idx.reshape(q, k)]
            kth.append(dist_c[:, -1])
            self._improve(P, np.repeat(np.arange(q), k), idx.ravel(), dbest, Yb, tri)
        for (members, tree, radius, k), dk in zip(self.groups, kth):
            # a triangle of this group closer than dbest has its centroid within dbest + radius
            unsure = np.nonzero((k < len(members)) & (dk < dbest + radius))[0]
            if not unsure.size:
                continue
            reach = (dbest[unsure] + radius) * (1 + 1e-9) + 1e-12 * self.bbox_diagonal
            cand = tree.query_ball_point(P[unsure], reach)
            counts = np.fromiter((len(c) for c in cand), dtype=np.int64, count=len(cand))
            f = np.fromiter((i for c in cand for i in c), dtype=np.int64, count=int(counts.sum()))
            self._improve(P, np.repeat(unsure, counts), members[f], dbest, Yb, tri)
        N = self._interpolated_normals(Yb, tri)
        return (Yb, N, tri) if return_index else (Yb, N)

    def _improve(self, P, owner, f, dbest, Yb, tri) -> None:
        """Test triangles ``f (c,)`` for points ``owner (c,)`` (sorted); keep the nearest in place."""
        if not len(f):
            return
        Y = closest_on_triangles(P[owner], self._A[f], self._B[f], self._C[f])
        d2 = np.einsum("ij,ij->i", Y - P[owner], Y - P[owner])
        # owner is sorted: segment minima, then the lowest triangle within TIE of each
        starts = np.flatnonzero(np.concatenate([[True], owner[1:] != owner[:-1]]))
        seg_min = np.minimum.reduceat(d2, starts)
        counts = np.diff(np.append(starts, len(d2)))
        at_min = np.flatnonzero(d2 <= np.repeat(seg_min, counts) * (1 + TIE))
        at_min = at_min[np.lexsort((f[at_min], owner[at_min]))]
        _, pos = np.unique(owner[at_min], return_index=True)
        first = at_min[pos]
        o = owner[first]
        b2 = dbest[o] ** 2
        better = (d2[first] < b2 * (1 - TIE)) | ((d2[first] <= b2 * (1 + TIE)) & (f[first] < tri[o]))
        better |= ~np.isfinite(dbest[o])
        o, pick = o[better], first[better]
        dbest[o], Yb[o], tri[o] = np.sqrt(d2[pick]), Y[pick], f[pick]

    def _interpolated_normals(self, Y: np.ndarray, tri: np.ndarray) -> np.ndarray:
        """(k, 3) unit normals at footpoints ``Y (k, 3)`` on triangles ``tri (k,)``:
        barycentric interpolation of the vertex normals (continuous across edges and
        vertices, so a footpoint on an edge gets one normal whichever triangle found it);
        the triangle normal where the interpolation degenerates."""
        A, B, C = self._A[tri], self._B[tri], self._C[tri]
        e0, e1, e2 = B - A, C - A, Y - A
        d00, d01, d11 = (np.einsum("ij,ij->i", a, b) for a, b in ((e0, e0), (e0, e1), (e1, e1)))
        d20, d21 = np.einsum("ij,ij->i", e2, e0), np.einsum("ij,ij->i", e2, e1)
        den = d00 * d11 - d01 * d01
        ok = den > 1e-14 * np.maximum(d00 * d11, 1e-300)
        den = np.where(ok, den, 1.0)
        v = (d11 * d20 - d01 * d21) / den
        w = (d00 * d21 - d01 * d20) / den
        Tv = self.normal_corners[tri]
        vn = self.normal_table
        N = (1 - v - w)[:, None] * vn[Tv[:, 0]] + v[:, None] * vn[Tv[:, 1]] + w[:, None] * vn[Tv[:, 2]]
        length = np.linalg.norm(N, axis=1)
        ok &= length > 1e-6
        return np.where(ok[:, None], N / np.where(ok, length, 1.0)[:, None], self.normals[tri])

    def distance(self, P: np.ndarray) -> np.ndarray:
        """(k,) float: exact distance of each point ``P (k, 3)`` to the reference."""
        Y, _ = self.closest(P)
        return np.linalg.norm(np.asarray(P).reshape(-1, 3) - Y, axis=1)
