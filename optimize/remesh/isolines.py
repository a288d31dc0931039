"""Quad-dominant mesh from two scalar functions: the arrangement of their integer iso-lines.

Given ``UV (n, 2)`` on the vertices of a triangle mesh with one or more
boundary loops (a disk or a disk with holes; the map is
assumed locally injective: :func:`optimize.remesh.quads.integrate` reports folds),
the lines ``u = i`` and ``v = j`` (integers, after a shift chosen to keep
lattice nodes away from the boundary) cut the parameter image of the surface
into cells.  Everything happens in the parameter plane, where it is a planar
arrangement; only the nodes are mapped back to 3D (barycentric interpolation
in the triangle that contains them).

- nodes: lattice points inside the boundary polygon, crossings of the lines
  with the boundary, and boundary corners of the input (turning angle above
  ``corner_angle``);
- edges: consecutive nodes along each line whose midpoint is inside, and
  consecutive boundary nodes along the boundary;
- faces: the bounded faces of the planar graph (a half-edge walk: the next
  half-edge is the clockwise neighbour of the twin), counter-clockwise;
- boundary: cells are clipped by the boundary, so boundary faces are
  triangles, quads or pentagons (rarely more where the boundary bends inside
  one cell); the boundary is straightened between consecutive boundary nodes.
  Boundary nodes closer than ``merge`` along the boundary are merged; a cell
  smaller than ``min_area`` (lattice cell = 1) that touches the boundary is
  snapped: its inner nodes collapse onto their nearest boundary node of the
  cell, so the full cell behind a sliver becomes the boundary cell.  (Merging
  the sliver into its neighbour instead left a T-junction pentagon with a
  corner of about 178 degrees, which the conical optimization dented past 180.)
  Small cells away from the boundary are merged into the neighbour across
  their longest inner edge (a T-junction turned into a pentagon, as in the
  paper), and a boundary node left with only two boundary edges is dropped.

Holes: the outer loop (largest parameter area) is counter-clockwise, holes
clockwise, the domain on the left of each; lattice nodes inside a hole are
dropped, the hole's boundary nodes form their own ring, and the faces inside a
hole (those running along its ring against its direction) are dropped.  A hole
not crossed by the lines raises MeshError.

No T-junctions arise otherwise: every crossing of two lines is a node of both.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..errors import ConfigError, MeshError
from ..mesh import Mesh


def locate(UV: np.ndarray, T: np.ndarray, Q: np.ndarray, k: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """Triangle ``(q,)`` and barycentric coordinates ``(q, 3)`` of points ``Q (q, 2)`` in the plane mesh ``UV, T``.

    Candidates are the ``k`` triangles with the nearest centroids; a point in
    none of them gets the candidate it is least outside of (clamped).
    """
    k = min(k, len(T))
    X = UV[T]  # (t, 3, 2)
    _, cand = cKDTree(X.mean(1)).query(Q, k=k)
    cand = cand.reshape(len(Q), k)
    A, B, C = X[cand, 0], X[cand, 1], X[cand, 2]  # (q, k, 2)
    d = (B[..., 0] - A[..., 0]) * (C[..., 1] - A[..., 1]) - (B[..., 1] - A[..., 1]) * (C[..., 0] - A[..., 0])
    d = np.where(np.abs(d) < 1e-300, 1e-300, d)
    Qk = Q[:, None, :]
    l1 = ((Qk[..., 0] - A[..., 0]) * (C[..., 1] - A[..., 1]) - (Qk[..., 1] - A[..., 1]) * (C[..., 0] - A[..., 0])) / d
    l2 = ((B[..., 0] - A[..., 0]) * (Qk[..., 1] - A[..., 1]) - (B[..., 1] - A[..., 1]) * (Qk[..., 0] - A[..., 0])) / d
    bary = np.stack([1 - l1 - l2, l1, l2], axis=-1)  # (q, k, 3)
    best = np.argmax(bary.min(-1), axis=1)
    rows = np.arange(len(Q))
    b = np.clip(bary[rows, best], 0, None)
    return cand[rows, best], b / b.sum(1, keepdims=True)


def planar_faces(P: np.ndarray, E: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounded faces of a planar straight-line graph.

    P : (N, 2) node positions, E : (e, 2) edges (no duplicates, no dangling edges).
    Returns ``(F (f, k) int padded with -1, counter-clockwise; area (f,))``.
    """
    ne = len(E)
    src, dst = np.concatenate([E[:, 0], E[:, 1]]), np.concatenate([E[:, 1], E[:, 0]])
    twin = (np.arange(2 * ne) + ne) % (2 * ne)
    d = P[dst] - P[src]
    label, size, start, nxt = face_cycles(src, np.arctan2(d[:, 1], d[:, 0]), twin)
    area = 0.5 * np.bincount(label, P[src, 0] * P[dst, 1] - P[dst, 0] * P[src, 1])
    keep = np.nonzero(area > 0)[0]
    return cycle_vertices(src, nxt, size, start, keep), area[keep]


def face_cycles(src: np.ndarray, angle: np.ndarray, twin: np.ndarray):
    """The face cycles of a graph embedded with half-edges ordered by angle at each node.

    src : (H,) int start node of each half-edge; angle : (H,) its direction angle at
    ``src``; twin : (H,) the opposite half-edge.  The next half-edge of a face is the
    clockwise neighbour of the twin at its node.  Returns ``label (H,)`` (cycle of
    each half-edge), ``size (c,)``, ``start (c,)`` (first half-edge of each cycle)
    and ``nxt (H,)``.
    """
    order = np.lexsort((angle, src))
    pos = np.empty_like(order)
    pos[order] = np.arange(len(order))
    s_sorted = src[order]
    first = np.searchsorted(s_sorted, src, side="left")
    last = np.searchsorted(s_sorted, src, side="right") - 1
    p = pos[twin]  # position of the twin among the half-edges leaving its node
    base = first[twin]
    prev = np.where(p - 1 >= base, p - 1, last[twin])
    nxt = order[prev]
    H = len(src)
    _, label = connected_components(coo_matrix((np.ones(H), (np.arange(H), nxt)), shape=(H, H)),
                                    directed=True, connection="weak")
    size = np.bincount(label)
    start = np.full(len(size), H, dtype=np.int64)
    np.minimum.at(start, label, np.arange(H))
    return label, size, start, nxt


def cycle_vertices(src, nxt, size, start, keep) -> np.ndarray:
    """(f, k) int, ``-1`` padded: the nodes of the cycles ``keep (f,)`` of :func:`face_cycles`."""
    k = int(size[keep].max()) if len(keep) else 3
    F = np.full((len(keep), k), -1, dtype=np.int64)
    cur = start[keep]
    for step in range(k):  # walk all faces at once, one step per vertex slot
        live = step < size[keep]
        F[live, step] = src[cur[live]]
        cur = nxt[cur]
    return F


def _boundary_loops(surface: Mesh, UV: np.ndarray) -> list[np.ndarray]:
    """Boundary loops of ``surface``, the outer one first and counter-clockwise in ``UV``, holes clockwise.

    The outer loop is the one of largest parameter area.  Raises MeshError for a
    closed surface or several components.
    """
    loops = surface.topology.boundary_loops
    if not loops or surface.topology.n_components != 1:
        raise MeshError(f"{surface.name}: {len(loops)} boundary loop(s), {surface.topology.n_components} "
                        "component(s); remeshing supports one component with at least one boundary loop")

    def area(loop):
        B = UV[loop]
        return 0.5 * np.sum(B[:, 0] * np.roll(B[:, 1], -1) - np.roll(B[:, 0], -1) * B[:, 1])

    a = np.array([area(lp) for lp in loops])  # one value per loop (a handful)
    outer = int(np.argmax(np.abs(a)))
    out = [loops[outer] if a[outer] > 0 else loops[outer][::-1]]
    out += [lp if a[k] < 0 else lp[::-1] for k, lp in enumerate(loops) if k != outer]
    return out


class _Boundary:
    """All boundary loops as one polygon soup: ``B (b, 2)`` parameters, ``X (b, 3)`` points,
    ``nxt, prv (b,)`` neighbours within the loop, ``lab (b,)`` loop index (0 = outer)."""

    def __init__(self, loops: list[np.ndarray], UV: np.ndarray, V: np.ndarray):
        sizes = np.array([len(lp) for lp in loops])
        first = np.cumsum(sizes) - sizes
        idx = np.concatenate(loops)
        self.lab = np.repeat(np.arange(len(loops)), sizes)
        k = np.arange(len(idx))
        last = k == (first + sizes - 1)[self.lab]
        self.nxt = np.where(last, first[self.lab], k + 1)
        self.prv = np.empty_like(self.nxt)
        self.prv[self.nxt] = k
        self.B, self.X = UV[idx], V[idx]
        from matplotlib.path import (
            Path,  # point-in-polygon; imported here, not when the core loads
        )

        self.paths = [Path(np.vstack([self.B[self.lab == i], self.B[self.lab == i][:1]]), closed=True)
                      for i in range(len(loops))]

    def inside(self, Q: np.ndarray) -> np.ndarray:
        """(q,) bool: points ``Q (q, 2)`` inside the outer loop and outside every hole."""
        ok = self.paths[0].contains_points(Q)
        for hole in self.paths[1:]:  # one test per hole
            ok &= ~hole.contains_points(Q)
        return ok


def _corners(X: np.ndarray, prv: np.ndarray, nxt: np.ndarray, angle_deg: float) -> np.ndarray:
    """(b,) bool: boundary polygon vertices ``X (b, 3)`` where it turns by more than ``angle_deg``."""
    a = X - X[prv]
    b = X[nxt] - X
    c = np.einsum("ij,ij->i", a, b) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-300)
    return c < np.cos(np.radians(angle_deg))


def _best_shift(B: np.ndarray, nxt: np.ndarray, trials: int = 5, near: float = 0.25) -> np.ndarray:
    """(2,) lattice shift that leaves the fewest lattice nodes within ``near`` of the boundary segments ``B -> B[nxt]``."""
    seg = B[nxt] - B
    L = np.linalg.norm(seg, axis=1)
    m = np.maximum(np.ceil(L / 0.05).astype(np.int64), 1)
    k = np.repeat(np.arange(len(B)), m)
    t = (np.arange(m.sum()) - np.repeat(np.cumsum(m) - m, m)) / m[k]
    tree = cKDTree(B[k] + t[:, None] * seg[k])
    lo, hi = np.floor(B.min(0)) - 1, np.ceil(B.max(0)) + 1
    I, J = np.meshgrid(np.arange(lo[0], hi[0] + 1), np.arange(lo[1], hi[1] + 1), indexing="ij")
    G = np.stack([I.ravel(), J.ravel()], 1)
    offs = np.arange(trials) / trials
    best, score = np.zeros(2), np.inf
    for a in offs:  # a handful of trial shifts
        for b in offs:
            s = np.sum(tree.query(G + [a, b], distance_upper_bound=near)[0] < near)
            if s < score:
                best, score = np.array([a, b]), s
    return best


def extract(surface: Mesh, UV: np.ndarray, *, corner_angle: float = 35.0, merge: float = 0.35,
            min_area: float = 0.25, name: str = "remeshed") -> tuple[Mesh, np.ndarray]:
    """Quad-dominant mesh of the integer iso-lines of ``UV (n, 2)`` on the triangle mesh ``surface``.

    ``surface`` is one component with one or more boundary loops (a disk, or a
    disk with holes); the parameter image must be one-to-one.
    Returns ``(mesh, corners)``: a Mesh whose vertices lie on ``surface`` (see
    the module docstring), with one boundary loop per input loop, and the
    ``(c,)`` indices of its vertices at corners of the input boundary.
    Raises ConfigError when no lattice node falls inside (edge length too
    large) and MeshError when a hole is too small to be crossed by the lines.
    """
    loops = _boundary_loops(surface, UV)
    bd = _Boundary(loops, UV, surface.V)
    UV = UV - _best_shift(bd.B, bd.nxt)
    bd = _Boundary(loops, UV, surface.V)
    B, X, nxt = bd.B, bd.X, bd.nxt
    lo, hi = np.floor(B.min(0)), np.ceil(B.max(0))
    I, J = np.meshgrid(np.arange(lo[0], hi[0] + 1), np.arange(lo[1], hi[1] + 1), indexing="ij")
    G = np.stack([I.ravel(), J.ravel()], 1)
    G = G[bd.inside(G)]
    if len(G) < 4:
        raise ConfigError(f"{surface.name}: only {len(G)} grid node(s) inside the surface; expected a "
                          "smaller edge length")
    # boundary nodes: crossings with the lines u = i, v = j, and corners
    B1, X1 = B[nxt], X[nxt]
    seg_k, seg_s, seg_axis = [], [], []
    for ax in (0, 1):
        a, b = B[:, ax], B1[:, ax]
        cnt = (np.floor(np.maximum(a, b)) - np.floor(np.minimum(a, b))).astype(np.int64)
        k = np.repeat(np.arange(len(B)), cnt)
        c = np.floor(np.minimum(a, b))[k] + 1 + (np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt))
        seg_k.append(k)
        seg_s.append((c - a[k]) / (b[k] - a[k]))
        seg_axis.append(np.full(len(k), ax))
    corner = np.nonzero(_corners(X, bd.prv, nxt, corner_angle))[0]
    seg_k.append(corner)
    seg_s.append(np.zeros(len(corner)))
    seg_axis.append(np.full(len(corner), 2))
    bk, bs, bax = (np.concatenate(x) for x in (seg_k, seg_s, seg_axis))
    order = np.lexsort((bs, bk))  # loop by loop (loops are contiguous in bk), along each loop
    bk, bs, bax = bk[order], bs[order], bax[order]
    blab = bd.lab[bk]
    bP = B[bk] + bs[:, None] * (B1[bk] - B[bk])
    bX = X[bk] + bs[:, None] * (X1[bk] - X[bk])
    snap = bax < 2
    bP[snap, bax[snap]] = np.round(bP[snap, bax[snap]])  # exactly on its line
    # merge boundary nodes closer than `merge` (parameter units) along the same loop; corners win
    gap = np.linalg.norm(np.roll(bP, -1, axis=0) - bP, axis=1)
    rep = np.arange(len(bP))
    close = (gap[:-1] < merge) & (blab[1:] == blab[:-1])
    for i in np.nonzero(close)[0].tolist():  # the few close pairs along the boundary
        a, b = int(rep[i]), i + 1
        keep, drop = (b, a) if bax[b] == 2 and bax[a] != 2 else (a, b)
        rep[rep == drop] = keep
    nG = len(G)
    P = np.vstack([G, bP])
    bnode = nG + np.arange(len(bP))
    node_loop = np.concatenate([np.full(nG, -1), blab])
    # line edges: consecutive nodes along u = i (axis 0) and v = j (axis 1)
    edges = []
    for ax in (0, 1):
        on = np.concatenate([np.arange(nG), bnode[bax == ax]])
        line, along = np.round(P[on, ax]), P[on, 1 - ax]
        o = np.lexsort((along, line))
        on, line = on[o], line[o]
        same = line[1:] == line[:-1]
        a, b = on[:-1][same], on[1:][same]
        mid = 0.5 * (P[a] + P[b])
        ok = bd.inside(mid)
        edges.append(np.stack([a[ok], b[ok]], 1))
    nodemap = np.arange(len(P))
    nodemap[bnode] = bnode[rep]
    ring = np.unique(bnode[rep])  # boundary order is index order, loop after loop
    edges.append(_ring_edges(ring, node_loop))
    E = nodemap[np.concatenate(edges)]
    E = E[E[:, 0] != E[:, 1]]
    E = np.unique(np.sort(E, axis=1), axis=0)
    is_corner = np.zeros(len(P), dtype=bool)
    is_corner[bnode[bax == 2]] = True
    E, ring = _cleanup(P, E, ring, node_loop, is_corner, min_area, merge)
    F, _ = _domain_faces(P, E, ring, node_loop)
    used = np.unique(F[F >= 0])
    _check_connected(surface, E, used, ring, node_loop, len(loops))
    # 3D positions: lattice nodes by point location, boundary nodes on the boundary polyline
    tri, bary = locate(UV, surface.F, P[:nG])
    X3 = np.vstack([np.einsum("qk,qkj->qj", bary, surface.V[surface.F[tri]]), bX])
    remap = np.full(len(P), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    out = Mesh(X3[used], np.where(F >= 0, remap[np.maximum(F, 0)], -1), name=name)
    out.notes.append(f"{name}: {int(np.sum(out.face_sizes == 4))} quads, "
                     f"{int(np.sum(out.face_sizes != 4))} other faces (boundary cells, merged small cells)")
    corners = remap[np.nonzero(is_corner)[0]]
    return out, np.sort(corners[corners >= 0])


def _check_connected(surface, E, used, ring, node_loop, n_loops):
    """Raise MeshError when a boundary loop lost its nodes or the line graph falls apart (a hole inside one cell)."""
    N = len(node_loop)
    have = np.bincount(node_loop[ring], minlength=n_loops)
    if np.any(have < 3):
        bad = int(np.argmin(have))
        raise MeshError(f"{surface.name}: boundary loop {bad} keeps only {int(have[bad])} node(s) after "
                        "extraction (a hole smaller than one cell); expected a smaller edge length")
    _, lab = connected_components(coo_matrix((np.ones(len(E)), (E[:, 0], E[:, 1])), shape=(N, N)),
                                      directed=False)
    if len(np.unique(lab[used])) > 1:
        raise MeshError(f"{surface.name}: the iso-lines fall into {len(np.unique(lab[used]))} separate pieces "
                        "(a hole inside one cell); expected a smaller edge length")


def _collapse_short(P, E, ring, node_loop, is_corner, merge):
    """Collapse edges shorter than ``merge``: each cluster becomes one node (a corner, else a boundary node).

    Edges joining two different boundary loops are never collapsed (that would merge a hole into its neighbour).
    """
    N = len(P)
    short = np.linalg.norm(P[E[:, 0]] - P[E[:, 1]], axis=1) < merge
    la, lb = node_loop[E[:, 0]], node_loop[E[:, 1]]
    short &= ~((la >= 0) & (lb >= 0) & (la != lb))
    if not short.any():
        return E, ring
    S = E[short]
    _, lab = connected_components(coo_matrix((np.ones(len(S)), (S[:, 0], S[:, 1])), shape=(N, N)),
                                  directed=False)
    on_ring = np.zeros(N, dtype=bool)
    on_ring[ring] = True
    prio = np.where(is_corner, 0, np.where(on_ring, 1, 2))
    order = np.lexsort((np.arange(N), prio, lab))  # best node first in every cluster
    head = np.zeros(N, dtype=np.int64)
    first = np.insert(lab[order][1:] != lab[order][:-1], 0, True)
    head[lab[order][first]] = order[first]
    rep = head[lab]
    E = rep[E]
    E = np.unique(np.sort(E[E[:, 0] != E[:, 1]], axis=1), axis=0)
    ring = rep[ring]
    return E, ring[ring != ring[ring_next(ring, node_loop)]]


def ring_next(ring: np.ndarray, node_loop: np.ndarray) -> np.ndarray:
    """(b,) position in ``ring`` of the next node along the same loop (rings are stored loop after loop)."""
    lab = node_loop[ring]
    k = np.arange(len(ring))
    start = np.insert(lab[1:] != lab[:-1], 0, True)
    first = np.maximum.accumulate(np.where(start, k, 0))
    last = np.append(lab[1:] != lab[:-1], True)
    return np.where(last, first, k + 1)


def _ring_edges(ring: np.ndarray, node_loop: np.ndarray) -> np.ndarray:
    """(b, 2) sorted edges between consecutive boundary nodes of every loop."""
    E = np.sort(np.stack([ring, ring[ring_next(ring, node_loop)]], 1), axis=1)
    return E[E[:, 0] != E[:, 1]]


def _domain_faces(P, E, ring, node_loop):
    """Bounded faces of the graph that lie in the domain (not the inside of a hole): ``(F (f, k), area (f,))``.

    Faces are counter-clockwise, the domain is on the left of every loop, so a
    face that runs along a loop against its direction is a hole.
    """
    F, area = planar_faces(P, E)
    N = len(P)
    face, a, b = cycle_edges(F)
    against = ring[ring_next(ring, node_loop)] * N + ring  # directed (next -> node)
    hole = np.bincount(face, np.isin(a * N + b, against), minlength=len(F)) > 0
    return F[~hole], area[~hole]


def _cleanup(P, E, ring, node_loop, is_corner, min_area, merge, rounds: int = 8):
    """Prune, snap or merge small cells, drop lone boundary nodes.  Returns ``(E (e, 2), ring (b,))``.

    P : (N, 2) nodes, E : (e, 2) sorted edges, ring : (b,) boundary nodes in
    order, loop after loop; node_loop : (N,) loop of each boundary node (-1 inside).
    """
    N = len(P)
    for _ in range(rounds):  # each round is vectorized; a few rounds settle everything
        on_ring = np.zeros(N, dtype=bool)
        on_ring[ring] = True
        while True:  # dangling edges, then boundary nodes with nothing but two boundary edges
            deg = np.bincount(E.ravel(), minlength=N)
            dangling = (deg == 1)
            lone = on_ring & (deg == 2) & ~is_corner
            if not (dangling.any() or lone.any()):
                break
            E = E[~(dangling[E[:, 0]] | dangling[E[:, 1]] | lone[E[:, 0]] | lone[E[:, 1]])]
            if lone.any():
                ring = ring[~lone[ring]]
                on_ring[:] = False
                on_ring[ring] = True
                E = np.unique(np.vstack([E, _ring_edges(ring, node_loop)]), axis=0)
        E, ring = _collapse_short(P, E, ring, node_loop, is_corner, merge)
        F, area = _domain_faces(P, E, ring, node_loop)
        small = np.nonzero(area < min_area)[0]
        if not len(small):
            break
        on_ring[:] = False
        on_ring[ring] = True
        E, snapped = _snap_small(P, E, F[small], on_ring)
        if snapped:
            continue
        E = _merge_small(P, E, F[small], ring, node_loop)
    return E, ring


def least_per_key(key: np.ndarray, value: np.ndarray) -> np.ndarray:
    """(u,) int: for each distinct ``key (k,)``, the position of its smallest ``value (k,)``."""
    o = np.lexsort((value, key))
    return o[np.insert(key[o][1:] != key[o][:-1], 0, True)]


def cycle_edges(F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Directed edges of the ``-1`` padded cycles ``F (f, k)``: ``(cell (h,), a (h,), b (h,))``."""
    a, b = F, np.roll(F, -1, axis=1)
    last = (F >= 0).sum(1) - 1
    b[np.arange(len(F)), last] = F[:, 0]
    ok = a >= 0
    return np.nonzero(ok)[0], a[ok], b[ok]


def _snap_small(P, E, cells, on_ring):
    """Collapse the inner nodes of small boundary cells onto their nearest boundary node in the same cell.

    A sliver between an iso-line and the boundary then disappears and the
    lattice nodes next to it become boundary nodes (they move by the sliver's
    width), instead of a merge that leaves a straight-angled T-junction beside
    the boundary.  Each inner node goes to one boundary node.  Returns ``(E,
    snapped)``; ``snapped`` is False when no small cell has an inner node next
    to a boundary node.
    """
    _, a, b = cycle_edges(cells)
    i, r = np.concatenate([a, b]), np.concatenate([b, a])  # (inner node, boundary node) pairs, both ways
    pick = ~on_ring[i] & on_ring[r]
    i, r = i[pick], r[pick]
    if not len(i):
        return E, False
    k = least_per_key(i, np.linalg.norm(P[i] - P[r], axis=1))
    rep = np.arange(len(P))
    rep[i[k]] = r[k]
    E = rep[E]
    return np.unique(np.sort(E[E[:, 0] != E[:, 1]], axis=1), axis=0), True


def _merge_small(P, E, cells, ring, node_loop):
    """Merge each small cell into its neighbour across its longest non-boundary edge (a T-junction)."""
    N = len(P)
    fa, ea, eb = cycle_edges(cells)
    key = np.minimum(ea, eb) * N + np.maximum(ea, eb)
    rk = _ring_edges(ring, node_loop)
    inner = ~np.isin(key, rk[:, 0] * N + rk[:, 1])
    fa, key = fa[inner], key[inner]
    if not len(key):
        return E
    length = np.linalg.norm(P[key // N] - P[key % N], axis=1)
    return E[~np.isin(E[:, 0] * N + E[:, 1], key[least_per_key(fa, -length)])]
