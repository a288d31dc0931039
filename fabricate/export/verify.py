"""Geometry checks on files read back: OCC face polygons, overlapping parts, panels on beams.

Used by :func:`fabricate.check.check_outputs`; every function takes data
read from the files (never the in-memory parts).  :func:`not_regular` says which paths the
check and its readers refuse to open.
"""
from __future__ import annotations

import os
import stat

import numpy as np

from .separation import overlapping_boxes, separated

KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a named pipe"), (stat.S_ISSOCK, "a socket"),
         (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"))


def not_regular(path) -> str | None:
    """What ``path`` is when it is there and not a regular file (``"a named pipe"``, ``"a folder"``, ...),
    from ``os.stat`` alone: it is never opened (a pipe or a device may never end).  None for a regular
    file or nothing there."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return None
    if stat.S_ISREG(mode):
        return None
    return next((what for test, what in KINDS if test(mode)), "not a regular file")


def face_polygons(shape) -> list[np.ndarray]:
    """Outer-wire corner loops ``(k, 3)`` of every face of an OCC solid, in wire order
    (counter-clockwise about the outward normal), for straight-edged planar faces."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Surface
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
        axis = BRepAdaptor_Surface(face).Plane().Axis().Direction()     # the plane's normal; the face's
        n = np.array([axis.X(), axis.Y(), axis.Z()]) * (-1.0 if face.Orientation() == TopAbs_REVERSED else 1.0)
        newell = np.cross(P, np.roll(P, -1, axis=0)).sum(axis=0)
        out.append(P if newell @ n > 0 else P[::-1])                  # counter-clockwise about it
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


def outline_areas(outlines: list[np.ndarray]) -> np.ndarray:
    """``(m,)`` areas of planar 2D polygons ``[(k, 2), ...]`` (shoelace about each first corner, as
    :func:`polygon_measures`), all at once."""
    k = np.array([len(Q) for Q in outlines], dtype=np.int64)
    if not len(k) or not (k > 0).all():                                 # none, or some without corners: 0
        out = np.zeros(len(outlines))
        if (k > 0).any():
            out[k > 0] = outline_areas([Q for Q in outlines if len(Q)])
        return out
    P = np.concatenate(outlines)
    first = np.concatenate([[0], np.cumsum(k)[:-1]])
    Q = P - np.repeat(P[first], k, axis=0)
    nxt = np.arange(len(P)) + 1
    nxt[first + k - 1] = first
    cz = Q[:, 0] * Q[nxt, 1] - Q[:, 1] * Q[nxt, 0]
    return 0.5 * np.abs(np.add.reduceat(cz, first))


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


def match_outlines(outlines: list[np.ndarray], faces: list[list[np.ndarray]]) -> tuple[np.ndarray, np.ndarray,
                                                                                   np.ndarray]:
    """:func:`match_outline` of every ``outlines[i] (k_i, 2 or 3)`` against ``faces[i]``: ``(face
    index (n,) int, area rel error (n,), max edge error mm (n,))``, the same figures to the last
    digit.  The outlines matched against one face of their own corner count (a flat outline: the
    usual case) are done ``k`` at a time, the rest one at a time."""
    n = len(outlines)
    fi, rel, err = np.full(n, -1, dtype=np.int64), np.full(n, np.inf), np.full(n, np.inf)
    by_k: dict[tuple[int, int], list[int]] = {}
    for i, (Q, F) in enumerate(zip(outlines, faces)):
        if len(F) == 1 and len(F[0]) == len(Q) and len(Q) and Q.ndim == 2 and Q.shape[1] in (2, 3) \
                and F[0].ndim == 2 and F[0].shape[1] == 3:
            by_k.setdefault((len(Q), Q.shape[1]), []).append(i)
        else:
            fi[i], rel[i], err[i] = match_outline(Q, F)
    for (k, d), ix in by_k.items():
        O = np.stack([outlines[i] for i in ix]).astype(float)               # (c, k, d)
        if d == 2:
            O = np.concatenate([O, np.zeros(O.shape[:2] + (1,))], axis=2)
        P = np.stack([faces[i][0] for i in ix]).astype(float)               # (c, k, 3)
        nxt = _next(k)
        a2, e2 = _measures(O, nxt)
        a3, E = _measures(P, nxt)
        shifts = e2[:, _SHIFTS[k]]                                           # (c, k, k): row s = roll(e2, s)
        both = np.stack([E, E[:, ::-1]], axis=1)                             # (c, 2, k)
        e = np.abs(both[:, :, None, :] - shifts[:, None, :, :]).max(axis=3).min(axis=2)   # (c, 2)
        ix = np.asarray(ix)
        fi[ix] = 0
        rel[ix] = np.abs(a3 - a2) / np.maximum(a3, 1e-300)
        err[ix] = e[np.arange(len(ix)), np.argmin(e, axis=1)]
    return fi, rel, err


def _measures(P: np.ndarray, nxt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`polygon_measures` of ``P (c, k, 3)``: areas ``(c,)`` and edge lengths ``(c, k)``, summed
    in the same order (the cross products corner after corner, the squares of a vector's three)."""
    Q = P - P[:, :1]
    C = _cross(Q, Q[:, nxt])                                                 # (c, k, 3)
    acc = C[:, 0].copy()
    for j in range(1, C.shape[1]):                                          # sum over the corners, in order
        acc += C[:, j]
    area = 0.5 * np.sqrt((acc ** 2).sum(axis=1))
    D = P[:, nxt] - P
    return area, np.sqrt((D * D).sum(axis=2))


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

    @property
    def face_support(self) -> tuple[np.ndarray, np.ndarray]:
        """``(normals (q, 3), offsets (q,))`` of the face planes with the whole solid on their inner
        side (all of them when it is convex; a notched beam's sides, top and bottom)."""
        if getattr(self, "_face_support", None) is None:
            keep = (self.normals @ self.V.T - self.offsets[:, None]).max(axis=1) <= self.tol
            self._face_support = (self.normals[keep], self.offsets[keep])
        return self._face_support

    def separates(self, other: Solid, tol: float) -> bool:
        """True when a supporting plane of this solid (a face plane, or a face of its convex hull) has
        all of ``other`` outside (touching allowed): their interiors are then disjoint."""
        n, c = self.support_planes
        d = other.V @ n.T - c[None, :]
        return bool((d.min(axis=0) >= -tol).any())


def _by_shape(objects: list[tuple[np.ndarray, np.ndarray]]) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Meshes grouped by ``(vertices, triangles)`` counts: ``[(indices (g,), V (g, nv, 3), T (g, t, 3))]``."""
    shape: dict[tuple[int, int], list[int]] = {}
    for k, (V, T) in enumerate(objects):
        shape.setdefault((len(V), len(T)), []).append(k)
    return [(np.array(ix), np.stack([objects[i][0] for i in ix]).astype(float), np.stack([objects[i][1] for i in ix]))
            for ix in shape.values()]


PER_CHUNK = 1 << 16
"""Triangle-vertex products per chunk of meshes in :func:`solids_of` (a chunk's temporaries stay in
the processor's cache: about ten times faster than one pass over a group of big meshes)."""


def _shape_figures(V: np.ndarray, T: np.ndarray):
    """Areas ``(g,)``, unit normals ``(g, t, 3)``, plane offsets ``(g, t)``, tolerances ``(g,)`` and each
    triangle plane's worst vertex ``(g, t)`` (largest signed distance outside it) of ``g`` meshes of one
    shape ``V (g, nv, 3)``, ``T (g, t, 3)``, in chunks of :data:`PER_CHUNK` triangle-vertex products."""
    g, t, nv = len(V), T.shape[1], V.shape[1]
    area, tol = np.empty(g), np.empty(g)
    N, off, worst = np.empty((g, t, 3)), np.empty((g, t)), np.empty((g, t))
    step = max(1, PER_CHUNK // max(t * nv, 1))
    for i in range(0, g, step):
        X, Y = V[i:i + step], T[i:i + step]
        r = np.arange(len(X))[:, None]
        A, B, C = X[r, Y[:, :, 0]], X[r, Y[:, :, 1]], X[r, Y[:, :, 2]]             # (c, t, 3)
        cr = _cross(B - A, C - A)
        norm = np.sqrt((cr * cr).sum(axis=2))
        area[i:i + step] = 0.5 * norm.sum(axis=1)
        n = N[i:i + step]
        np.divide(cr, np.maximum(norm, 1e-300)[:, :, None], out=n)
        off[i:i + step] = (n * A).sum(axis=2)
        size = np.sqrt(((X.max(axis=1) - X.min(axis=1)) ** 2).sum(axis=1))
        tol[i:i + step] = 1e-9 * np.maximum(size, 1.0)
        np.matmul(n, X.transpose(0, 2, 1)).max(axis=2, out=worst[i:i + step])
    worst -= off                        # max(d - c) = max(d) - c exactly: rounding is monotone
    return area, N, off, tol, worst


def solids_of(objects: dict[str, tuple[np.ndarray, np.ndarray]]) -> dict[str, Solid]:
    """:class:`Solid` of every mesh ``{name: (V (nv, 3), T (t, 3))}``, their planes, areas and
    convexity computed for all meshes of one shape at once (the same figures as ``Solid(name, V, T)``)."""
    names = list(objects)
    meshes = [objects[n] for n in names]
    if not names or any(len(V) == 0 or len(T) == 0 for V, T in meshes):
        return {n: Solid(n, *objects[n]) for n in names}
    out: list[Solid | None] = [None] * len(names)
    new = Solid.__new__
    for ix, V, T in _by_shape(meshes):
        area, N, off, tol, per_tri = _shape_figures(V, T)
        keep = per_tri <= tol[:, None]
        convex = keep.all(axis=1)
        for r, k, a, c, cv in zip(range(len(ix)), ix.tolist(), area.tolist(), tol.tolist(), convex.tolist()):
            s = new(Solid)
            s.name, (s.V, s.T) = names[k], meshes[k]
            s.area, s.normals, s.offsets, s.tol, s.convex = a, N[r], off[r], c, cv
            s._manifold = s._planes = None
            s._face_support = (N[r], off[r]) if cv else (N[r][keep[r]], off[r][keep[r]])
            out[k] = s
    return dict(zip(names, out))


def _separated(solids: list[Solid], a: np.ndarray, b: np.ndarray, tol: float, hull: bool) -> np.ndarray:
    """``(q,) bool``: a supporting plane of ``solids[a]`` has all of ``solids[b]`` outside (within
    ``tol``): :meth:`Solid.separates` for every pair at once (pairs bucketed by plane and vertex
    counts, :func:`fabricate.export.separation.separated`).  With ``hull`` False only face planes with
    the whole part on one side are tried (no convex hull)."""
    if not len(a):
        return np.zeros(0, bool)
    used = np.unique(np.concatenate([a, b])).tolist()
    planes: list = [None] * len(solids)
    corners: list = [None] * len(solids)
    for i in used:
        s = solids[i]
        planes[i] = s.support_planes if hull else s.face_support
        corners[i] = s.V
    return separated(planes, corners, a, b, tol)


def intersections(solids: list[Solid], linear_tol: float) -> dict:
    """Overlap volumes of every pair of parts whose boxes overlap.

    A pair is cleared by a separating supporting plane of either part (a face
    plane of a convex part, a face of the convex hull of a non-convex one:
    exact for touching parts), tested for all pairs at once; otherwise manifold3d
    computes the intersection volume, which must stay below ``linear_tol x`` the
    smaller surface area.
    """
    n = np.array([len(s.V) for s in solids], dtype=np.int64)
    if len(solids) and (n > 0).all():
        V, first = np.concatenate([s.V for s in solids]), np.concatenate([[0], np.cumsum(n)[:-1]])
        lo, hi = np.minimum.reduceat(V, first), np.maximum.reduceat(V, first)
    else:
        lo = np.array([s.V.min(axis=0) for s in solids]).reshape(-1, 3)
        hi = np.array([s.V.max(axis=0) for s in solids]).reshape(-1, 3)
    pairs = overlapping_boxes(lo, hi, pad=linear_tol)
    a, b = pairs[:, 0], pairs[:, 1]
    rest = np.ones(len(pairs), bool)
    for hull in (False, True):                  # supporting face planes first, convex hulls for the rest
        for x, y in ((a, b), (b, a)):
            rest[rest] = ~_separated(solids, x[rest], y[rest], linear_tol, hull)
    by_plane, booleans, worst, worst_pair, failures = int(len(pairs) - rest.sum()), 0, 0.0, None, []
    for a, b in pairs[rest].tolist():  # pairs not cleared by a plane: few
        A, B = solids[a], solids[b]
        booleans += 1
        vol = float((A.manifold ^ B.manifold).volume())
        limit = linear_tol * min(A.area, B.area)
        if vol > worst:
            worst, worst_pair = vol, (A.name, B.name)
        if vol > limit:
            failures.append({"pair": [A.name, B.name], "volume_mm3": vol, "limit_mm3": limit})
    return {"pass": not failures, "parts": len(solids), "box_pairs": len(pairs),
            "cleared_by_plane": by_plane, "boolean_pairs": booleans, "max_volume_mm3": worst,
            "worst_pair": worst_pair, "tolerance": f"{linear_tol:g} mm x smaller surface area",
            "failures": failures[:20], "failed": len(failures)}


WITNESS_REL = 1e-3
"""A point of one part within ``WITNESS_REL x linear_tol`` (1e-6 mm) of every face plane of a convex
part (inside it up to the files' rounding: 12 digits in the 3MF, 4e-8 mm at 40 m) proves the two
touch: its distance to that part is below ``linear_tol`` unless two of its faces meet at less than
``2 asin(WITNESS_REL)``, about 0.11 degrees (no panel or beam has such a sliver).  A pair without
such a point (a gap, or coordinates so large that their rounding exceeds it) goes to min_gap."""


def _witnessed(solids: dict[str, Solid], pairs: list[tuple[str, str]], delta: float) -> np.ndarray:
    """``(q,) bool``: a corner, triangle-edge midpoint or triangle centroid of one part of each pair
    lies in the other (a convex part, within ``delta`` of its face planes), for all pairs at once;
    and ``(q,)`` the best witness's largest distance outside a face plane (mm)."""
    names = sorted({n for p in pairs for n in p})
    k = {n: i for i, n in enumerate(names)}
    S = [solids[n] for n in names]
    cand: list[np.ndarray | None] = [None] * len(S)
    for ix, V, T in _by_shape([(s.V, s.T) for s in S]):      # corners, edge midpoints, centroids
        g = np.arange(len(ix))[:, None, None]
        X = V[g, T]                                            # (g, t, 3, 3)
        pts = np.concatenate([V, (0.5 * (X + np.roll(X, 1, axis=2))).reshape(len(ix), -1, 3),
                              X.mean(axis=2)], axis=1)
        for r, i in enumerate(ix.tolist()):
            cand[i] = pts[r]
    M = max(len(c) for c in cand)
    F = max(len(s.normals) for s in S)
    Cp = np.zeros((len(S), M, 3))
    Np = np.zeros((len(S), F, 3))
    Op = np.full((len(S), F), np.inf)                          # padding: never the plane that is violated
    for i, (c, s) in enumerate(zip(cand, S)):
        Cp[i, :len(c)], Cp[i, len(c):] = c, c[0]
        if s.convex:
            Np[i, :len(s.normals)], Op[i, :len(s.normals)] = s.normals, s.offsets
        else:
            Op[i] = -np.inf                                     # not convex: no witness inside it
    a = np.array([k[p] for p, _ in pairs], dtype=np.int64)
    b = np.array([k[q] for _, q in pairs], dtype=np.int64)
    best = np.full(len(pairs), np.inf)
    corners = max(len(s.V) for s in S)
    for m in (corners, M):              # the corners first (the first points of every part), then all
        todo = np.flatnonzero(best > delta)
        step = max(1, 4_000_000 // (m * F))
        for i in range(0, len(todo), step):
            t = todo[i:i + step]
            for x, y in ((a[t], b[t]), (b[t], a[t])):
                d = np.matmul(Np[y], Cp[x, :m].transpose(0, 2, 1)) - Op[y][:, :, None]
                d = np.where(np.isnan(d), np.inf, d)
                best[t] = np.minimum(best[t], d.max(axis=1).min(axis=1))
    return best <= delta, np.maximum(best, 0.0)


def bearing(solids: dict[str, Solid], supports: dict[str, list[str]], linear_tol: float) -> dict:
    """Gap between every panel and each beam it should bear on.

    A pair is settled at once when a corner, edge midpoint or triangle centroid of one part lies in the other (convex)
    part: gap 0 (:data:`WITNESS_REL`); every other pair gets manifold3d's ``min_gap``."""
    worst, worst_pair, failures, n = 0.0, None, [], 0
    pairs = []
    for pid, beams in supports.items():
        for bid in beams:
            if pid not in solids or bid not in solids:
                failures.append({"pair": [pid, bid], "missing": True})
            else:
                pairs.append((pid, bid))
    touch, outside = _witnessed(solids, pairs, WITNESS_REL * linear_tol) if pairs else (np.zeros(0, bool),
                                                                                         np.zeros(0))
    for (pid, bid), ok in zip(pairs, touch.tolist()):
        n += 1
        if ok:
            continue
        gap = float(solids[pid].manifold.min_gap(solids[bid].manifold, 10.0))
        if gap > worst:
            worst, worst_pair = gap, (pid, bid)
        if gap > linear_tol:
            failures.append({"pair": [pid, bid], "gap_mm": gap})
    return {"pass": not failures, "pairs": n, "touching_by_witness": int(touch.sum()),
            "witness_off_plane_mm_max": float(outside[touch].max()) if touch.any() else 0.0,
            "min_gap_pairs": n - int(touch.sum()), "max_gap_mm": worst, "worst_pair": worst_pair,
            "tolerance_mm": linear_tol, "failures": failures[:20], "failed": len(failures)}
