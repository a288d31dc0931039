"""Quad mesh of the integer iso-lines of a seamless parametrization, traced on the surface.

Input: a triangle mesh, per-corner parameters ``UVc (t, 3, 2)`` (a cut
parametrization) and, per half-edge, the transition into the twin face's
chart ``uv' = M^r uv + t`` (``r`` quarter turns, ``t`` integer).  Because the
transitions map the integer lattice to itself, the iso-lines ``u = i``,
``v = j`` continue across cuts; no planar arrangement is needed:

- nodes: lattice points inside triangles (merged by 3D position where a
  point lies on an edge, or on both sides of a cut), crossings of the lines
  with the boundary, and boundary corners;
- edges: from every lattice node, a trace in each of the four directions
  ``+-u, +-v`` (one vectorized step per triangle crossed, all traces at once)
  to the next lattice node or to the boundary; from every boundary crossing a
  trace inward along its line (lines that clip a corner of the domain); and
  the boundary between consecutive boundary nodes;
- faces: orbits of the half-edges, with the edges at each node ordered by
  angle in the node's tangent plane; the orbits outside the boundary are dropped.

A singular vertex at a lattice node gets the 3 or 5 traces of its wedges (a
valence-3/5 vertex); one at a cell centre is surrounded by a 3- or 5-gon.
Tiny boundary cells and close boundary nodes are left to
:func:`optimize.remesh.boundary_cells.snap_slivers`, which :func:`optimize.remesh.quads.remesh`
applies to the traced mesh.
"""
from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..errors import MeshError
from ..mesh import Mesh
from .isolines import cycle_vertices, face_cycles, ring_next
from .seamless import rotation

LATTICE_SLACK = 1e-6  # barycentric slack when finding lattice nodes in triangles
NEAR = 0.3  # parameter distance along a trace at which its direction at a node is taken
_DIRS = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])


def _bary(A: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """(k, 3) barycentric coordinates of ``Q (k, 2)`` in the triangles ``A (k, 3, 2)``."""
    e1, e2, q = A[:, 1] - A[:, 0], A[:, 2] - A[:, 0], Q - A[:, 0]
    d = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    l1 = (q[:, 0] * e2[:, 1] - q[:, 1] * e2[:, 0]) / d
    l2 = (e1[:, 0] * q[:, 1] - e1[:, 1] * q[:, 0]) / d
    return np.stack([1 - l1 - l2, l1, l2], 1)


def trace_quads(mesh: Mesh, UVc: np.ndarray, rot: np.ndarray, shift: np.ndarray, *, corner_angle: float = 35.0,
                name: str = "traced", max_steps: int = 2000) -> tuple[Mesh, np.ndarray]:
    """Quad-dominant Mesh of the integer iso-lines, and ``(c,)`` vertices at boundary corners.

    mesh : triangle Mesh (its topology gives twins and boundary loops);
    UVc : (t, 3, 2) per-corner parameters; rot : (3t,) int and shift : (3t, 2)
    transition of every half-edge into its twin's chart.
    Raises MeshError when the traces do not close up (a folded parametrization).
    """
    t = mesh.topology
    V, F = mesh.V, mesh.F
    nt = len(F)
    V3 = V[F]
    scale = float(np.linalg.norm(V3[:, 1] - V3[:, 0], axis=1).mean())
    tol3 = 1e-5 * scale
    # -- lattice nodes -------------------------------------------------------
    lo, hi = np.ceil(UVc.min(1) - 1e-9), np.floor(UVc.max(1) + 1e-9)
    cnt = np.maximum(hi - lo + 1, 0).astype(np.int64)
    m = cnt[:, 0] * cnt[:, 1]
    f = np.repeat(np.arange(nt), m)
    k = np.arange(m.sum()) - np.repeat(np.cumsum(m) - m, m)
    Q = lo[f] + np.stack([k // cnt[f, 1], k % cnt[f, 1]], 1)
    lam = _bary(UVc[f], Q)
    ok = lam.min(1) >= -LATTICE_SLACK  # a singular vertex sits on its node only to the solver's precision
    f, Q, lam = f[ok], Q[ok], np.clip(lam[ok], 0, 1)
    P3 = np.einsum("kc,kcj->kj", lam, V3[f])
    node = _merge_points(P3, tol3)
    n_lat = int(node.max()) + 1 if len(node) else 0
    X_lat = np.zeros((n_lat, 3))
    X_lat[node] = P3
    # -- boundary crossings -------------------------------------------------
    bh = np.nonzero(t.twin < 0)[0]
    bf, bj = bh // 3, bh % 3
    a, b = UVc[bf, bj], UVc[bf, (bj + 1) % 3]
    bk, bs, bax = [], [], []
    for ax in (0, 1):
        lo_, hi_ = np.minimum(a[:, ax], b[:, ax]), np.maximum(a[:, ax], b[:, ax])
        first = np.floor(lo_) + 1
        c = np.maximum(np.floor(hi_) - first + 1, 0).astype(np.int64)  # integers in (lo, hi]
        kk = np.repeat(np.arange(len(bh)), c)
        val = first[kk] + np.arange(c.sum()) - np.repeat(np.cumsum(c) - c, c)
        s = (val - a[kk, ax]) / (b[kk, ax] - a[kk, ax])
        keep = (s > 1e-9) & (s < 1 - 1e-9)
        bk.append(kk[keep]), bs.append(s[keep]), bax.append(np.full(keep.sum(), ax))
    bk, bs, bax = np.concatenate(bk), np.concatenate(bs), np.concatenate(bax)
    Xa, Xb = V[t.corner_vertex[bh]], V[t.corner_next_vertex[bh]]
    X_bnd = Xa[bk] + bs[:, None] * (Xb[bk] - Xa[bk])
    # boundary corners of the input
    loops = t.boundary_loops
    if not loops:
        raise MeshError(f"{mesh.name}: closed surface, expected a boundary")
    L = np.concatenate(loops)
    lab = np.repeat(np.arange(len(loops)), [len(lp) for lp in loops])
    pos = np.arange(len(L))
    start = np.repeat(np.cumsum([len(lp) for lp in loops]) - [len(lp) for lp in loops], [len(lp) for lp in loops])
    size = np.repeat([len(lp) for lp in loops], [len(lp) for lp in loops])
    nx, pv = L[start + (pos - start + 1) % size], L[start + (pos - start - 1) % size]
    u1, u2 = V[L] - V[pv], V[nx] - V[L]
    cosang = np.einsum("ij,ij->i", u1, u2) / np.maximum(np.linalg.norm(u1, axis=1) * np.linalg.norm(u2, axis=1), 1e-300)
    corner_v = L[cosang < np.cos(np.radians(corner_angle))]
    # boundary position of every mesh vertex along its loop, and of every crossing
    loop_pos = np.full(len(V), -1.0)
    loop_pos[L] = pos
    loop_of = np.full(len(V), -1)
    loop_of[L] = lab
    va = t.corner_vertex[bh]
    along = loop_pos[va][bk] + bs  # boundary half-edges run along the loops
    n_b = len(X_bnd)
    X_all = np.vstack([X_lat, X_bnd, V[corner_v]])
    b_ids = n_lat + np.arange(n_b)
    c_ids = n_lat + n_b + np.arange(len(corner_v))
    ring_pos = np.concatenate([along, loop_pos[corner_v]])
    ring_lab = np.concatenate([loop_of[va][bk], loop_of[corner_v]])
    ring_ids = np.concatenate([b_ids, c_ids])
    # -- traces --------------------------------------------------------------
    # from lattice candidates: 4 directions that enter the candidate's triangle
    tf = np.repeat(f, 4)
    tp = np.repeat(Q, 4, axis=0).astype(float)
    td = np.tile(_DIRS, (len(f), 1))
    inn = _bary(UVc[tf], tp + 1e-7 * td).min(1) >= -1e-12
    tf, tp, td, tsrc = tf[inn], tp[inn], td[inn], np.repeat(node, 4)[inn]
    # from boundary crossings: inward along their line
    cf = bf[bk]
    cp = a[bk] + bs[:, None] * (b[bk] - a[bk])
    cp[np.arange(n_b), bax] = np.round(cp[np.arange(n_b), bax])
    dpos = np.where(bax[:, None] == 0, [[0.0, 1.0]], [[1.0, 0.0]])
    cd = np.where((_bary(UVc[cf], cp + 1e-7 * dpos).min(1) >= -1e-12)[:, None], dpos, -dpos)
    tf, tp, td = np.concatenate([tf, cf]), np.vstack([tp, cp]), np.vstack([td, cd])
    tsrc = np.concatenate([tsrc, b_ids])
    # distance to the next integer along the direction
    along_c = np.einsum("ij,ij->i", tp, np.abs(td))
    sign = np.einsum("ij,ij->i", td, np.ones_like(td))
    nxt_int = np.where(sign > 0, np.floor(along_c + 1e-9) + 1, np.ceil(along_c - 1e-9) - 1)
    rem = np.abs(nxt_int - along_c)
    end_face, end_p, end_kind, _, left = _march(t, UVc, rot, shift, tf, tp, td, rem, max_steps)
    end3 = _point(UVc, V3, end_face, end_p)
    # directions at both ends for the angular order around the nodes: chords to the points a
    # little way along the trace (a Jacobian at the node itself misleads where the parameters
    # are distorted, around a singular node: up to 60 degrees there, enough to swap two edges)
    travelled = np.where(end_kind == 1, rem - left, rem)
    step = np.minimum(NEAR, 0.5 * travelled)
    fa, pa, _, _, _ = _march(t, UVc, rot, shift, tf, tp, td, step, max_steps)
    fb, pb, _, _, _ = _march(t, UVc, rot, shift, tf, tp, td, travelled - step, max_steps)
    start3 = _point(UVc, V3, tf, tp)
    dir0 = _point(UVc, V3, fa, pa) - start3
    dir1 = _point(UVc, V3, fb, pb) - end3
    # endpoints: nearest lattice node (kind 0) or boundary node (kind 1)
    tdst = np.full(len(tf), -1)
    if n_lat:
        d0, i0 = cKDTree(X_lat).query(end3)
        sel = (end_kind == 0) & (d0 < 1e-3 * scale + 10 * tol3)
        tdst[sel] = i0[sel]
    if n_b:
        d1, i1 = cKDTree(X_bnd).query(end3)
        sel = (end_kind == 1) & (d1 < 1e-3 * scale + 10 * tol3)
        tdst[sel] = b_ids[i1[sel]]
    lost = int(np.sum(tdst < 0))
    good = (tdst >= 0) & (tdst != tsrc)
    src, dst, dir0, dir1 = tsrc[good], tdst[good], dir0[good], dir1[good]
    # one edge per node pair (a trace and its reverse)
    key = np.minimum(src, dst) * len(X_all) + np.maximum(src, dst)
    _, first = np.unique(key, return_index=True)
    src, dst, dir0, dir1 = src[first], dst[first], dir0[first], dir1[first]
    # ring edges, loop by loop along the boundary direction
    o = np.lexsort((ring_pos, ring_lab))
    r_ids, r_lab = ring_ids[o], ring_lab[o]
    nxt = ring_next(np.arange(len(r_ids)), r_lab)  # the next node along the same loop
    if np.any(np.bincount(r_lab, minlength=len(loops)) < 3):
        raise MeshError(f"{mesh.name}: a boundary loop is crossed by fewer than 3 iso-lines (a hole inside "
                        "one cell); expected a smaller edge length")
    ra, rb = r_ids, r_ids[nxt]
    chord = X_all[rb] - X_all[ra]
    src = np.concatenate([src, ra])
    dst = np.concatenate([dst, rb])
    dir0 = np.concatenate([dir0, chord])
    dir1 = np.concatenate([dir1, -chord])
    is_ring = np.concatenate([np.zeros(len(first), dtype=bool), np.ones(len(ra), dtype=bool)])
    # a trace that runs along the boundary between two consecutive boundary nodes repeats a ring edge
    nn = len(X_all)
    pair = np.minimum(src, dst) * nn + np.maximum(src, dst)
    keep = is_ring | ~np.isin(pair, pair[is_ring])
    keep &= _prune_dangling(src, dst, nn, keep)  # a lost trace leaves its partner edge hanging
    src, dst, dir0, dir1, is_ring = src[keep], dst[keep], dir0[keep], dir1[keep], is_ring[keep]
    Fq = _faces(X_all, src, dst, dir0, dir1, is_ring, mesh, name)
    used = np.unique(Fq[Fq >= 0])
    remap = np.full(len(X_all), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    out = Mesh(X_all[used], np.where(Fq >= 0, remap[np.maximum(Fq, 0)], -1), name=name)
    if lost:  # the face count is noted by the caller, after the boundary clean-up
        out.notes.append(f"{name}: {lost} trace(s) lost")
    corners = remap[c_ids]
    return out, np.sort(corners[corners >= 0])


def _point(UVc: np.ndarray, V3: np.ndarray, f: np.ndarray, p: np.ndarray) -> np.ndarray:
    """(k, 3) surface points of the parameter points ``p (k, 2)`` in the charts of faces ``f (k,)``."""
    return np.einsum("kc,kcj->kj", _bary(UVc[f], p).clip(0, 1), V3[f])


def _merge_points(P: np.ndarray, tol: float) -> np.ndarray:
    """(k,) labels of points ``P (k, 3)`` merged when closer than ``tol``."""
    pairs = cKDTree(P).query_pairs(tol, output_type="ndarray")
    A = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(P), len(P)))
    return connected_components(A, directed=False)[1]


def _march(t, UVc, rot, shift, f, p, d, rem, max_steps):
    """Follow all traces at once, one triangle per step.

    Returns per trace the final face, point (in that face's chart), kind
    (0 reached its lattice node, 1 hit the boundary, 2 lost), direction and
    the parameter distance left to go (0 for kind 0).
    """
    f, p, d, rem = f.copy(), p.copy(), d.copy(), rem.copy()
    kind = np.full(len(f), 2)
    entry = np.full(len(f), -1)  # local edge we came in through
    live = np.arange(len(f))
    for _ in range(max_steps):  # one triangle crossed per step
        if not len(live):
            break
        ff, pp, dd = f[live], p[live], d[live]
        A = UVc[ff]
        l0 = _bary(A, pp)
        l1 = _bary(A, pp + dd) - l0  # derivative along the direction
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(l1 < -1e-15, -l0 / l1, np.inf)
        # edge opposite corner c is local edge (c + 1) % 3
        loc = (np.arange(3)[None, :] + 1) % 3
        s = np.where(loc == entry[live][:, None], np.inf, s)
        s = np.maximum(s, 0)
        c = np.argmin(s, 1)
        sx = s[np.arange(len(live)), c]
        arrive = rem[live] <= sx + 1e-9
        done = live[arrive]
        p[done] = pp[arrive] + rem[done][:, None] * dd[arrive]
        kind[done] = 0
        go = live[~arrive]
        cg = c[~arrive]
        he = 3 * f[go] + (cg + 1) % 3
        x = pp[~arrive] + sx[~arrive][:, None] * dd[~arrive]
        tw = t.twin[he]
        hit = tw < 0
        p[go[hit]] = x[hit]
        kind[go[hit]] = 1
        rem[go[hit]] -= sx[~arrive][hit]
        cont = go[~hit]
        he, x, tw = he[~hit], x[~hit], tw[~hit]
        M = rotation(rot[he]).astype(float)
        p[cont] = np.einsum("kij,kj->ki", M, x) + shift[he]
        d[cont] = np.einsum("kij,kj->ki", M, d[cont])
        rem[cont] -= sx[~arrive][~hit]
        f[cont] = tw // 3
        entry[cont] = tw % 3
        live = cont
    rem[kind == 0] = 0.0
    return f, p, kind, d, rem


def _prune_dangling(src: np.ndarray, dst: np.ndarray, n: int, keep: np.ndarray) -> np.ndarray:
    """(e,) bool: the edges ``src -> dst`` among ``keep (e,) bool`` left after repeatedly
    removing edges at nodes of degree 1."""
    keep = keep.copy()
    while True:  # each pass removes the current dead ends; chains take a few passes
        deg = np.bincount(src[keep], minlength=n) + np.bincount(dst[keep], minlength=n)
        dead = keep & ((deg[src] == 1) | (deg[dst] == 1))
        if not dead.any():
            return keep
        keep &= ~dead


def _faces(X, src, dst, dir0, dir1, is_ring, mesh, name):
    """Faces ``(f, k)`` of the graph: half-edge orbits with edges ordered by angle at every node."""
    ne = len(src)
    hs = np.concatenate([src, dst])
    hdir = np.concatenate([dir0, dir1])
    twin = (np.arange(2 * ne) + ne) % (2 * ne)
    # node normals from the triangle surface: nearest vertex normal
    Fm = mesh.F
    fn = np.cross(mesh.V[Fm[:, 1]] - mesh.V[Fm[:, 0]], mesh.V[Fm[:, 2]] - mesh.V[Fm[:, 0]])
    Nv = np.zeros_like(mesh.V)
    for j in range(3):  # the three corners of every triangle
        np.add.at(Nv, Fm[:, j], fn)
    _, near = cKDTree(mesh.V).query(X)
    n = Nv[near] / np.maximum(np.linalg.norm(Nv[near], axis=1, keepdims=True), 1e-300)
    e1 = np.cross(n, np.array([0.2718281828, 0.5772156649, 0.7071067812]))
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(n, e1)
    ang = np.arctan2(np.einsum("ij,ij->i", hdir, e2[hs]), np.einsum("ij,ij->i", hdir, e1[hs]))
    label, size, start, nxt = face_cycles(hs, ang, twin)
    outside = np.zeros(label.max() + 1, dtype=bool)
    outside[label[ne:][is_ring]] = True  # ring edges run with the surface on their left
    keep = np.nonzero(~outside)[0]
    k = int(size[keep].max()) if len(keep) else 3
    if k > 12:
        raise MeshError(f"{name}: a traced cell has {k} corners; the parametrization folds or a trace was "
                        "lost; expected a locally injective parametrization")
    return cycle_vertices(hs, nxt, size, start, keep)
