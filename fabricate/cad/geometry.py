"""Vectorized kernels for planar-faced polyhedra given as planes and polygons.

Planes are ``(normal, offset)`` pairs with ``normal . x = offset``.  A batch
of ``p`` polyhedra of one combinatorial type shares one face list ``faces``
(tuple of vertex-index tuples, outward orientation) and stores its vertices
as ``V (p, nv, 3)``.
"""
from __future__ import annotations

import numpy as np


def unit(x: np.ndarray) -> np.ndarray:
    """``x (..., 3)`` scaled to unit length (zero vectors stay zero)."""
    n = np.linalg.norm(x, axis=-1, keepdims=True)
    return x / np.where(n > 0, n, 1.0)


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise dot product of ``(..., 3)`` arrays."""
    return np.einsum("...i,...i->...", a, b)


def meet3(n1, o1, n2, o2, n3, o3) -> tuple[np.ndarray, np.ndarray]:
    """Intersection points of plane triples.

    n1, n2, n3 : (..., 3) float normals; o1, o2, o3 : (...,) float offsets.
    Returns ``X (..., 3)`` and ``det (...,)`` (``|det|`` near 0: nearly
    parallel planes, the point is unreliable).  Solved by Cramer's rule with
    cross products: ``X = (o1 n2 x n3 + o2 n3 x n1 + o3 n1 x n2) / det``.
    """
    c23, c31, c12 = np.cross(n2, n3), np.cross(n3, n1), np.cross(n1, n2)
    det = dot(n1, c23)
    safe = np.where(np.abs(det) > 1e-300, det, 1.0)
    X = (o1[..., None] * c23 + o2[..., None] * c31 + o3[..., None] * c12) / safe[..., None]
    return X, det


def line_plane(p: np.ndarray, d: np.ndarray, n: np.ndarray, o: np.ndarray) -> np.ndarray:
    """Points where lines ``p + s d`` meet planes ``n . x = o`` (all ``(..., 3)`` / ``(...,)``)."""
    s = (o - dot(n, p)) / dot(n, d)
    return p + s[..., None] * d


def fan_triangles(faces: tuple[tuple[int, ...], ...]) -> np.ndarray:
    """(t, 3) int: fan triangulation of every face (faces are convex and planar)."""
    tris = [(f[0], f[j], f[j + 1]) for f in faces for j in range(1, len(f) - 1)]
    return np.asarray(tris, dtype=np.int64).reshape(-1, 3)


def volumes(V: np.ndarray, faces) -> np.ndarray:
    """(p,) float: volumes of closed polyhedra ``V (p, nv, 3)`` (divergence theorem).

    Exact for planar faces; computed about each polyhedron's first vertex to
    avoid cancellation far from the origin.
    """
    T = fan_triangles(faces)
    X = V - V[:, :1, :]
    a, b, c = X[:, T[:, 0]], X[:, T[:, 1]], X[:, T[:, 2]]
    return dot(a, np.cross(b, c)).sum(axis=1) / 6.0


def convexity(P: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(p,) float: min over corners of ``(e_in x e_out) . normal / (|e_in| |e_out|)``.

    P : (p, k, 3) polygons, normal : (p, 3) expected unit normals.  Positive
    when every polygon is strictly convex and turns counter-clockwise about
    ``normal``; zero or negative flags a fold, a reversal or a collapsed edge.
    """
    e_out = np.roll(P, -1, axis=1) - P
    e_in = P - np.roll(P, 1, axis=1)
    s = dot(np.cross(e_in, e_out), normal[:, None, :])
    den = np.linalg.norm(e_in, axis=2) * np.linalg.norm(e_out, axis=2)
    return (s / np.where(den > 0, den, 1.0) * (den > 0)).min(axis=1)


def plane_fit(P: np.ndarray, normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Offset ``(p,)`` of the best plane with a given ``normal (p, 3)`` through ``P (p, k, 3)``,
    and the largest distance ``(p,)`` of a point from it (mm)."""
    h = dot(P, normal[:, None, :])
    o = h.mean(axis=1)
    return o, np.abs(h - o[:, None]).max(axis=1)


def flat_frame(P: np.ndarray, normal: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A rigid 2D frame in the plane of each polygon.

    P : (p, k, 3) planar polygons, normal : (p, 3) the side the viewer looks from.
    Returns ``origin (p, 3)``, ``ex (p, 3)``, ``ey (p, 3)`` with ``ex`` along the
    first edge and ``ey = normal x ex``: 2D coordinates are
    ``((x - origin) . ex, (x - origin) . ey)``, a rigid motion, so edge
    lengths and areas are kept exactly, and a polygon counter-clockwise about
    ``normal`` stays counter-clockwise in the plane.
    """
    origin = P[:, 0]
    ex = unit(P[:, 1] - P[:, 0])
    ex = unit(ex - dot(ex, normal)[:, None] * normal)
    ey = np.cross(normal, ex)
    return origin, ex, ey


def min_area_rectangle(Q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Smallest bounding rectangle of 2D polygons, aligned with one of their edges.

    Q : (p, k, 2) float.  Returns the rotation angle ``(p,)`` (radians; rotate
    the polygon by it to make the rectangle axis-aligned) and its width
    ``(p,)`` and height ``(p,)`` (width >= height).  Exact for convex polygons
    (the optimal rectangle has a side on an edge of the convex hull).
    """
    E = np.roll(Q, -1, axis=1) - Q
    ang = -np.arctan2(E[..., 1], E[..., 0])  # (p, k) candidate rotations
    c, s = np.cos(ang), np.sin(ang)
    # rotated x and y of every vertex for every candidate: (p, k_candidates, k_vertices)
    x = c[:, :, None] * Q[:, None, :, 0] - s[:, :, None] * Q[:, None, :, 1]
    y = s[:, :, None] * Q[:, None, :, 0] + c[:, :, None] * Q[:, None, :, 1]
    w = x.max(axis=2) - x.min(axis=2)
    h = y.max(axis=2) - y.min(axis=2)
    best = np.argmin(w * h, axis=1)
    idx = np.arange(len(Q))
    W, H, A = w[idx, best], h[idx, best], ang[idx, best]
    swap = H > W
    A = np.where(swap, A + np.pi / 2, A)
    return A, np.maximum(W, H), np.minimum(W, H)


def rotate2d(Q: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """(p, k, 2): polygons ``Q (p, k, 2)`` rotated counter-clockwise by ``angle (p,)``."""
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    return np.stack([c * Q[..., 0] - s * Q[..., 1], s * Q[..., 0] + c * Q[..., 1]], axis=2)


def polygon_area_2d(Q: np.ndarray) -> np.ndarray:
    """(p,) float: signed area of 2D polygons ``Q (p, k, 2)`` (shoelace, positive CCW)."""
    R = Q - Q[:, :1]
    x, y = R[..., 0], R[..., 1]
    return 0.5 * (x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y).sum(axis=1)
