"""Exact closest points for an optimizer's iterates: candidate triangles kept between calls.

An iteration moves the vertices a little, so the triangles that can hold a
vertex's closest point hardly change.  For every query point ``p0`` this
keeps the triangles ``T`` with

    dist(p0, T) <= u + 2 M,     u = dist(p0, T0) for some triangle T0,

where ``M`` is a margin.  While a point ``p`` stays within ``M`` of ``p0``
these candidates contain its closest triangle ``T*``: ``dist(p, T*) <=
dist(p, T0) <= u + M``, hence ``dist(p0, T*) <= u + 2 M``.  A query then tests
only its few candidates, exactly (the Voronoi-region test of
:func:`optimize.proximity.surface.closest_on_triangles`); a point that moved farther
than ``M`` gets new candidates (a ball query on the triangle centroids with
radius ``u + 2 M + R``, ``R`` the largest centroid-to-vertex radius, then the
distance to each triangle's bounding box, a lower bound, then the exact
distance; with the compiled kernels of :mod:`optimize.kernels` and up
to ``SCAN_MAX`` point-triangle pairs, the box and exact tests run on every
triangle instead, which finds the same candidates without the ball query).
``T0`` is the point's last closest triangle, or the nearest centroid's at the
first call; the compiled warm query tests it first and skips candidates whose
bounding box is farther than the best distance found.

The answers equal :meth:`optimize.proximity.surface.Reference.closest`'s: the same
distances and footpoints to rounding, normals by the reference's own
interpolation (``Reference._interpolated_normals``).  Ties are broken the same
way: of the triangles whose squared distance is within
:data:`optimize.proximity.surface.TIE` of the least the lowest index wins, so a
point as close to two triangles (on a symmetry plane of the reference, or
equidistant from two separate parts of it) gets the same answer whatever the
rounding and the order of the candidates.
When the candidate sets would be large (very unequal triangle sizes make
``R`` loose), or a query point is not finite, queries are handed to
``Reference.closest`` unchanged.
"""
from __future__ import annotations

from itertools import chain

import numpy as np
from scipy.spatial import cKDTree

from .. import kernels
from .surface import TIE, Reference, closest_on_triangles

MAX_CANDIDATES = 64  # mean candidates per point beyond which Reference.closest is used
SCAN_MAX = 2_000_000  # (points x triangles) up to which renewals test every triangle (compiled)


class Footpoints:
    """Closest points and normals on ``ref`` for query sets ``P (q, 3)`` that move little per call.

    ref : Reference.  compiled : use the numba kernels where available (False: the
    NumPy path, which needs no compile/load time).  margin : ``M`` above, in the units of the reference
    (``optimize.solvers.paper.problem.Problem`` uses ``FOOT_MARGIN`` = 0.3 mean edge lengths, the default solver 0.1).
    Counters ``queries`` and ``rebuilt`` (points given new candidates) for the record.
    """

    def __init__(self, ref: Reference, margin: float, compiled: bool = True):
        self.ref, self.margin = ref, float(margin)
        self.compiled = bool(compiled)
        X = ref.mesh.V[ref.triangles]  # (t, 3, 3)
        self.A, self.B, self.C = (np.ascontiguousarray(X[:, i]) for i in range(3))
        self.T = np.ascontiguousarray(ref.normal_corners, dtype=np.int64)  # rows of ref.normal_table
        self.lo, self.hi = X.min(axis=1), X.max(axis=1)  # bounding boxes: a cheap lower bound first
        self.rmax = float(np.linalg.norm(X - ref.centroids[:, None, :], axis=2).max(initial=0.0))
        self.tree = cKDTree(ref.centroids)
        self.slack = 1e-12 * ref.bbox_diagonal
        self.P0 = self.tri = None
        self.delegate = False
        self.queries = self.rebuilt = 0

    def reset(self) -> None:
        """Forget the warm start (last query points, candidates, closest triangles): the next query
        answers as the first one did, so a run on a reused structure does not depend on earlier runs
        (ties between equally close triangles are broken the same way)."""
        self.P0 = self.tri = None
        self.delegate = False

    def closest(self, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``Y (q, 3)`` exact closest points on the reference and ``N (q, 3)`` unit normals there."""
        P = np.asarray(P, dtype=np.float64).reshape(-1, 3)
        self.queries += 1
        if self.delegate or not np.all(np.isfinite(P)):
            return self.ref.closest(P)
        if self.P0 is None or len(P) != len(self.P0):
            self.P0, self.tri = P.copy(), None
            self.owner = self.cand = np.zeros(0, dtype=np.int64)
            far = np.ones(len(P), dtype=bool)
        else:
            dP = P - self.P0
            far = np.einsum("ij,ij->i", dP, dP) > self.margin ** 2
        Y, tri = np.empty_like(P), np.empty(len(P), dtype=np.int64)
        if far.any():  # new candidates; the nearest of them is the answer
            idx = np.nonzero(far)[0]
            got = self._renew(P, idx)
            if got is None:
                self.delegate = True
                return self.ref.closest(P)
            Y[idx], tri[idx] = got
        k = kernels.get() if self.compiled else None
        if not far.all():
            if k is not None:  # the same search, compiled (optimize.kernels)
                prev = self.tri if self.tri is not None else np.full(len(P), -1, dtype=np.int64)
                Yk, tk, found = k.closest_candidates(P, self.A, self.B, self.C, self.owner, self.cand, far,
                                                     self.lo, self.hi, prev)
                Y[found], tri[found] = Yk[found], tk[found]
            else:
                sel = ~far[self.owner]
                o, f = self.owner[sel], self.cand[sel]
                pts, Y_, t_ = self._pick(o, f, *self._pairs(P, o, f))
                Y[pts], tri[pts] = Y_, t_
        self.tri = tri
        if k is not None:
            r = self.ref
            return Y, k.interpolated_normals(Y, tri, self.A, self.B, self.C, self.T, r.normal_table, r.normals)
        return Y, self.ref._interpolated_normals(Y, tri)

    def _pairs(self, P: np.ndarray, o: np.ndarray, f: np.ndarray):
        """Closest points ``(c, 3)`` of points ``o (c,)`` on triangles ``f (c,)``, squared distances ``(c,)``."""
        Po = P[o]
        Y = closest_on_triangles(Po, self.A[f], self.B[f], self.C[f])
        d = Y - Po
        return Y, np.einsum("ij,ij->i", d, d)

    @staticmethod
    def _pick(o: np.ndarray, f: np.ndarray, Y: np.ndarray, d: np.ndarray):
        """For pairs sorted by point ``o``: the points, and their nearest pair's closest point
        ``(k, 3)`` and triangle ``(k,)`` (the lowest triangle at ties: ``TIE``)."""
        starts = np.flatnonzero(np.concatenate([[True], o[1:] != o[:-1]]))
        counts = np.diff(np.append(starts, len(o)))
        hit = np.flatnonzero(d <= np.repeat(np.minimum.reduceat(d, starts), counts) * (1 + TIE))
        hit = hit[np.lexsort((f[hit], o[hit]))]
        first = hit[np.concatenate([[True], o[hit[1:]] != o[hit[:-1]]])]
        return o[first], Y[first], f[first]

    def _renew(self, P: np.ndarray, idx: np.ndarray):
        """New candidates for the points ``idx (k,)``, sorted, at ``P[idx]``.

        Returns their closest points ``(k, 3)`` and triangles ``(k,)``, or None if
        there would be too many candidates."""
        Pi = P[idx]
        t0 = self.tree.query(Pi, k=1)[1] if self.tri is None else self.tri[idx]
        k = kernels.get() if self.compiled else None
        if k is not None and len(idx) * len(self.A) <= SCAN_MAX:  # every triangle, compiled
            owner, f, Y, tri = k.scan_triangles(P, np.ascontiguousarray(idx, dtype=np.int64),
                                                np.ascontiguousarray(t0, dtype=np.int64), self.margin,
                                                self.slack, self.A, self.B, self.C, self.lo, self.hi)
            if len(f) > MAX_CANDIDATES * len(P) or np.any(tri < 0):
                return None
            return self._store(P, idx, owner, f, Y, tri)
        u = np.linalg.norm(closest_on_triangles(Pi, self.A[t0], self.B[t0], self.C[t0]) - Pi, axis=1)
        reach = (u + 2 * self.margin) * (1 + 1e-9) + self.slack  # (k,)
        lists = self.tree.query_ball_point(Pi, reach + self.rmax, return_sorted=False)
        counts = np.fromiter(map(len, lists), dtype=np.int64, count=len(lists))
        if counts.sum() > MAX_CANDIDATES * len(P) or counts.min(initial=1) == 0:
            return None  # (no candidate cannot happen: t0 qualifies, unless rounding defeats the slack)
        f = np.fromiter(chain.from_iterable(lists), dtype=np.int64, count=int(counts.sum()))
        owner = np.repeat(idx, counts)
        r = np.repeat(reach, counts)
        Po = P[owner]
        box = np.maximum(np.maximum(self.lo[f] - Po, Po - self.hi[f]), 0.0)  # distance to the box <= to T
        near = np.einsum("ij,ij->i", box, box) <= r * r * (1 + 1e-9)
        owner, f, r = owner[near], f[near], r[near]  # t0 stays: its box is within u <= reach
        Yc, d2 = self._pairs(P, owner, f)
        _, Y, tri = self._pick(owner, f, Yc, d2)  # every triangle that can be closest is a candidate
        keep = np.sqrt(d2) <= r
        return self._store(P, idx, owner[keep], f[keep], Y, tri)

    def _store(self, P, idx, owner, f, Y, tri):
        """Replace the candidates of the points ``idx`` by the pairs ``(owner, f)``; returns ``Y, tri``."""
        stay = ~np.isin(self.owner, idx)
        owner = np.concatenate([self.owner[stay], owner])
        f = np.concatenate([self.cand[stay], f])
        srt = np.argsort(owner, kind="stable")
        self.owner, self.cand = owner[srt], f[srt]
        self.P0[idx] = P[idx]
        self.rebuilt += len(idx)
        return Y, tri
