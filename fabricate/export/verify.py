"""Geometry checks on files read back: OCC face polygons, overlapping parts, panels on beams.

Used by :func:`fabricate.check.check_outputs`; every function takes data
read from the files (never the in-memory parts).
"""
from __future__ import annotations

import numpy as np


def face_polygons(shape) -> list[np.ndarray]:
    """Outer-wire corner loops ``(k, 3)`` of every face of an OCC solid, in wire order
    (counter-clockwise about the outward normal), for straight-edged planar faces."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepTools import BRepTools, BRepTools_WireExplorer
    from OCP.TopAbs import TopAbs_FACE, TopAbs_REVERSED
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    out = []
    ex = TopExp_Explorer(shape, TopAbs_FACE)
    while ex.More():
        face = TopoDS.Face(ex.Current())
        wx = BRepTools_WireExplorer(BRepTools.OuterWire_s(face), face)
        pts = []
        while wx.More():
            p = BRep_Tool.Pnt_s(wx.CurrentVertex())
            pts.append((p.X(), p.Y(), p.Z()))
            wx.Next()
        P = np.array(pts, dtype=float)
        out.append(P[::-1] if face.Orientation() == TopAbs_REVERSED else P)
        ex.Next()
    return out


def polygon_measures(P: np.ndarray) -> tuple[float, np.ndarray]:
    """Area and edge lengths ``(k,)`` of a planar polygon given in 2D ``(k, 2)`` or 3D ``(k, 3)``."""
    if P.shape[1] == 2:
        P = np.concatenate([P, np.zeros((len(P), 1))], axis=1)
    nxt = _NEXT.get(len(P)) if len(P) in _NEXT else _next(len(P))
    Q = P - P[0]
    area = 0.5 * float(np.sqrt((_cross(Q, Q[nxt]).sum(axis=0) ** 2).sum()))
    D = P[nxt] - P
    return area, np.sqrt((D * D).sum(axis=1))


_NEXT: dict[int, np.ndarray] = {}
_SHIFTS: dict[int, np.ndarray] = {}


def _next(k: int) -> np.ndarray:
    """(k,) index of the next corner (cached per k)."""
    if k not in _NEXT:
        _NEXT[k] = (np.arange(k) + 1) % k
        _SHIFTS[k] = (np.arange(k)[None, :] - np.arange(k)[:, None]) % k   # row s: np.roll(x, s)
    return _NEXT[k]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of ``(..., 3)`` arrays (np.cross without its axis handling)."""
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def match_outline(outline: np.ndarray, faces: list[np.ndarray]) -> tuple[int, float, float]:
    """The face of a solid a flat outline is a copy of: ``(face index, area rel error, max edge error mm)``.

    Compares edge-length sequences up to a cyclic shift or a reversal, then areas.
    """
    a2, e2 = polygon_measures(outline)
    k = len(outline)
    idx = [i for i, F in enumerate(faces) if len(F) == k]
    if not idx:
        return -1, np.inf, np.inf
    nxt = _next(k)
    P = np.stack([faces[i] for i in idx])                                # (c, k, 3)
    D = P[:, nxt] - P
    E = np.sqrt((D * D).sum(axis=2))                                     # (c, k)
    shifts = e2[_SHIFTS[k]]                                              # (k, k): row s = roll(e2, s)
    both = np.concatenate([E, E[:, ::-1]])                               # (2c, k)
    err = np.abs(both[:, None, :] - shifts[None, :, :]).max(axis=2).min(axis=1)
    best = int(np.argmin(err))
    a3, _ = polygon_measures(P[best % len(idx)])
    return idx[best % len(idx)], abs(a3 - a2) / max(a3, 1e-300), float(err[best])


def overlapping_boxes(lo: np.ndarray, hi: np.ndarray, pad: float = 0.0) -> np.ndarray:
    """(q, 2) int pairs ``i < j`` whose bounding boxes ``lo, hi (p, 3)`` overlap (sweep and prune on x)."""
    order = np.argsort(lo[:, 0], kind="stable")
    xl, xh = lo[order, 0], hi[order, 0]
    end = np.searchsorted(xl, xh + pad, side="right")
    start = np.arange(len(order)) + 1
    count = np.maximum(end - start, 0)
    i = np.repeat(np.arange(len(order)), count)
    j = start[i] + (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count))
    a, b = order[i], order[j]
    keep = np.all((lo[a] <= hi[b] + pad) & (lo[b] <= hi[a] + pad), axis=1)
    pairs = np.stack([np.minimum(a, b), np.maximum(a, b)], axis=1)[keep]
    return pairs


class Solid:
    """A closed triangle mesh read back (one part): planes, convexity, manifold3d object on demand."""

    def __init__(self, name: str, V: np.ndarray, T: np.ndarray):
        self.name, self.V, self.T = name, V, T
        A, B, C = V[T[:, 0]], V[T[:, 1]], V[T[:, 2]]
        cr = np.cross(B - A, C - A)
        self.area = 0.5 * float(np.linalg.norm(cr, axis=1).sum())
        self.normals = cr / np.maximum(np.linalg.norm(cr, axis=1, keepdims=True), 1e-300)
        self.offsets = np.einsum("ij,ij->i", self.normals, A)
        size = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
        self.tol = 1e-9 * max(size, 1.0)
        self.convex = bool((self.normals @ V.T - self.offsets[:, None]).max() <= self.tol)
        self._manifold = None
        self._planes = None

    @property
    def manifold(self):
        if self._manifold is None:
            import manifold3d

            self._manifold = manifold3d.Manifold(manifold3d.Mesh64(
                vert_properties=np.ascontiguousarray(self.V, dtype=np.float64),
                tri_verts=np.ascontiguousarray(self.T, dtype=np.uint64)))
        return self._manifold

    @property
    def support_planes(self) -> tuple[np.ndarray, np.ndarray]:
        """``(normals (q, 3), offsets (q,))`` of planes with the whole solid on their inner side: its
        face planes when it is convex, else the faces of its convex hull (a notched beam's end cut)."""
        if self._planes is None:
            if self.convex:
                self._planes = (self.normals, self.offsets)
            else:
                from scipy.spatial import ConvexHull

                eq = ConvexHull(self.V).equations                 # n . x + c <= 0 inside, |n| = 1
                self._planes = (eq[:, :3], -eq[:, 3])
        return self._planes

    def separates(self, other: "Solid", tol: float) -> bool:
        """True when a supporting plane of this solid (a face plane, or a face of its convex hull) has
        all of ``other`` outside (touching allowed): their interiors are then disjoint."""
        n, c = self.support_planes
        d = other.V @ n.T - c[None, :]
        return bool((d.min(axis=0) >= -tol).any())


def intersections(solids: list[Solid], linear_tol: float) -> dict:
    """Overlap volumes of every pair of parts whose boxes overlap.

    A pair is cleared by a separating supporting plane of either part (a face
    plane of a convex part, a face of the convex hull of a non-convex one:
    exact for touching parts); otherwise manifold3d computes the intersection volume,
    which must stay below ``linear_tol x`` the smaller surface area.
    """
    lo = np.array([s.V.min(axis=0) for s in solids]).reshape(-1, 3)
    hi = np.array([s.V.max(axis=0) for s in solids]).reshape(-1, 3)
    pairs = overlapping_boxes(lo, hi, pad=linear_tol)
    by_plane, booleans, worst, worst_pair, failures = 0, 0, 0.0, None, []
    for a, b in pairs.tolist():  # pairs in contact: a few per part
        A, B = solids[a], solids[b]
        if A.separates(B, linear_tol) or B.separates(A, linear_tol):
            by_plane += 1
            continue
        booleans += 1
        vol = float((A.manifold ^ B.manifold).volume())
        limit = linear_tol * min(A.area, B.area)
        if vol > worst:
            worst, worst_pair = vol, (A.name, B.name)
        if vol > limit:
            failures.append({"pair": [A.name, B.name], "volume_mm3": vol, "limit_mm3": limit})
    return {"pass": not failures, "parts": len(solids), "box_pairs": int(len(pairs)),
            "cleared_by_plane": by_plane, "boolean_pairs": booleans, "max_volume_mm3": worst,
            "worst_pair": worst_pair, "tolerance": f"{linear_tol:g} mm x smaller surface area",
            "failures": failures[:20], "failed": len(failures)}


def bearing(solids: dict[str, Solid], supports: dict[str, list[str]], linear_tol: float) -> dict:
    """Gap between every panel and each beam it should bear on (manifold3d ``min_gap``)."""
    worst, worst_pair, failures, n = 0.0, None, [], 0
    for pid, beams in supports.items():
        P = solids.get(pid)
        for bid in beams:
            B = solids.get(bid)
            if P is None or B is None:
                failures.append({"pair": [pid, bid], "missing": True})
                continue
            n += 1
            gap = float(P.manifold.min_gap(B.manifold, 10.0))
            if gap > worst:
                worst, worst_pair = gap, (pid, bid)
            if gap > linear_tol:
                failures.append({"pair": [pid, bid], "gap_mm": gap})
    return {"pass": not failures, "pairs": n, "max_gap_mm": worst, "worst_pair": worst_pair,
            "tolerance_mm": linear_tol, "failures": failures[:20], "failed": len(failures)}
