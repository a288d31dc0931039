"""Cross-field singularities kept: a cut surface and an integer-seamless parametrization.

Instead of smoothing the cross field until its singularities leave the patch,
each singularity (index ``+-1/4``) is kept at a vertex and becomes an
irregular vertex (valence 3 / 5) or an irregular face (a 3- / 5-gon) of the
quad mesh:

1. :func:`vertex_indices`: the index (in quarter turns) of a per-triangle
   cross field around every interior vertex (period jumps across the edges of
   its star, with the angle defect of the vertex);
2. :func:`cut_graph`: shortest paths (edge lengths) from every singular vertex
   to the boundary, and from every hole to the outer loop; their union is the cut;
3. :func:`cut_open`: the triangle mesh cut open along it (vertices on the cut
   duplicated, one copy per wedge of faces between cut edges);
4. :func:`seamless_uv`: the combed field on the cut mesh is consistent; across
   each cut edge the two sides differ by a rotation ``M^r`` (``r`` quarter
   turns) which the parameters must follow: ``uv_B = M^r uv_A + t``.  The
   least-squares integration of :func:`optimize.remesh.quads.integrate` runs with
   these transitions as (heavily weighted) linear constraints; the
   translations ``t`` are then rounded to integers one group (cut arc) at a
   time, re-solving in between.  Integer ``t`` maps integer iso-lines to
   integer iso-lines across the cut, and puts every singular vertex (a fixed
   point of ``uv -> M^r uv + t``) on a lattice node or a cell centre: a
   valence-3/5 vertex, or a 3-/5-gon.

The iso-lines of such a parametrization are extracted on the surface by
:func:`optimize.remesh.tracing.trace_quads` (a planar arrangement no longer exists:
the parameter image around a ``-1/4`` singularity covers 450 degrees).

Holes: each inner boundary loop is joined to the outer one by a cut too, so
the cut surface is a disk; the field's turn around a hole and the period of
``u, v`` around it become the transition across that cut (rotation from the
combed field, translation rounded to an integer like the others).

Not supported: singularities of index other than ``+-1/4`` (they are cut to
the boundary like the others, but give folded cells), closed surfaces; the
integer rounding is greedy (no branch and bound).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import connected_components, dijkstra

from ..errors import MeshError
from ..mesh import Mesh
from .crossfield import comb, face_frames

#: quarter turn acting on parameters ``(u, v)``: ``(u, v) -> (v, -u)`` (``X1 -> n x X1 = X2``)
M1 = np.array([[0, 1], [-1, 0]])


_STEPS = np.array([[a, b] for a in (-1, 0, 1) for b in (-1, 0, 1)], dtype=float)  # integer neighbours


def rotation(r) -> np.ndarray:
    """(..., 2, 2) int matrices ``M1^r`` for integer ``r`` (any shape)."""
    r = np.asarray(r) % 4
    Ms = np.stack([np.linalg.matrix_power(M1, k) for k in range(4)])
    return Ms[r]


def _angle_to(e: np.ndarray, X: np.ndarray, n: np.ndarray) -> np.ndarray:
    """(k,) angle from ``e (k, 3)`` to ``X (k, 3)`` about the normals ``n (k, 3)``."""
    return np.arctan2(np.einsum("ij,ij->i", np.cross(e, X), n), np.einsum("ij,ij->i", e, X))


def vertex_indices(mesh: Mesh, X1: np.ndarray) -> np.ndarray:
    """(n,) int index of the per-triangle cross field ``X1 (t, 3)`` at every vertex, in quarter turns.

    ``+1`` (index ``+1/4``) becomes a valence-3 vertex, ``-1`` a valence-5
    vertex; boundary vertices get 0.
    """
    t = mesh.topology
    V, F = mesh.V, mesh.F
    nf = face_frames(mesh)[0]
    c = np.arange(3 * len(F))
    f = c // 3
    v, a, b = t.corner_vertex, t.corner_next_vertex, t.corner_prev_vertex
    e_first, e_second = V[a] - V[v], V[b] - V[v]
    theta = _angle_to(e_first, e_second, nf[f])  # corner angle (ccw, in (0, pi))
    alpha_first = _angle_to(e_first, X1[f], nf[f])
    alpha_second = alpha_first - theta
    nxt = t.twin[t.corner_prev]  # the corner at v in the next face counter-clockwise (-1 on the boundary)
    ok = nxt >= 0
    d = alpha_first[np.maximum(nxt, 0)] - alpha_second
    q = np.pi / 2
    jump = d - q * np.round(d / q)  # wrapped into (-pi/4, pi/4]
    s = np.bincount(v[ok], jump[ok], minlength=len(V))  # turn of the field across the star's edges
    defect = 2 * np.pi - np.bincount(v, theta, minlength=len(V))  # angle defect (Gauss curvature)
    index = np.rint((s + defect) / q).astype(np.int64)
    index[t.is_boundary_vertex] = 0
    return index


def cut_graph(mesh: Mesh, singular: np.ndarray) -> np.ndarray:
    """(c, 2) sorted vertex pairs: the cut that opens ``mesh`` into a disk with ``singular (s,)`` on its rim.

    Shortest paths (edge lengths, boundary edges not crossed) from every
    singular vertex to the boundary, and, on a surface with several boundary
    loops (holes), from every loop to the outer loop or a loop already joined
    to it.  The union is the cut; cut open, the surface is simply connected, so
    the combed field has no mismatch left and every period of the
    parametrization is a transition across a cut arc.
    """
    t = mesh.topology
    E = t.edges
    n = len(mesh.V)
    loops = t.boundary_loops
    if not loops:
        raise MeshError(f"{mesh.name}: closed surface; singularities are cut to the boundary, expected one")
    L = np.linalg.norm(mesh.V[E[:, 1]] - mesh.V[E[:, 0]], axis=1)
    inner = ~t.is_boundary_edge
    G = sp.coo_matrix((L[inner], (E[inner, 0], E[inner, 1])), shape=(n, n)).tocsr()
    pairs = []

    def walk(pred, v):
        while pred[v] >= 0:
            pairs.append((min(v, pred[v]), max(v, pred[v])))
            v = pred[v]
        return v

    # holes: join loop after loop to the outer one (the longest), nearest first
    loop_of = np.full(n, -1)
    for k, lp in enumerate(loops):
        loop_of[lp] = k
    outer = int(np.argmax([np.linalg.norm(mesh.V[lp] - mesh.V[np.roll(lp, 1)], axis=1).sum() for lp in loops]))
    joined = np.zeros(len(loops), dtype=bool)
    joined[outer] = True
    while not joined.all():  # a handful of holes: one shortest path each
        src = np.nonzero(joined[np.maximum(loop_of, 0)] & (loop_of >= 0))[0]
        src = np.union1d(src, np.unique(np.array(pairs, dtype=np.int64)))
        dist, pred, _ = dijkstra(G, directed=False, indices=src, min_only=True, return_predecessors=True)
        cand = np.nonzero((loop_of >= 0) & ~joined[np.maximum(loop_of, 0)])[0]
        v = int(cand[np.argmin(dist[cand])])
        if not np.isfinite(dist[v]):
            raise MeshError(f"{mesh.name}: boundary loop {int(loop_of[v])} cannot be joined to the others")
        start = len(pairs)
        walk(pred, v)
        on_path = np.unique(np.array(pairs[start:], dtype=np.int64)) if len(pairs) > start else np.array([v])
        joined[np.unique(loop_of[on_path][loop_of[on_path] >= 0])] = True
    if len(singular):
        bnd = np.nonzero(t.is_boundary_vertex)[0]
        _, pred, _ = dijkstra(G, directed=False, indices=bnd, min_only=True, return_predecessors=True)
        for s in np.asarray(singular).tolist():  # a handful of singular vertices, one path each
            walk(pred, s)
    return np.unique(np.array(pairs, dtype=np.int64).reshape(-1, 2), axis=0)


def cut_open(mesh: Mesh, cut: np.ndarray) -> tuple[Mesh, np.ndarray, np.ndarray]:
    """The triangle mesh cut open along the edges ``cut (c, 2)``.

    Returns ``(cut_mesh, corner_copy (3t,), is_cut_he (3t,) bool)``: the cut
    Mesh (same faces, in the same order, on duplicated vertices), the cut-mesh
    vertex of every corner of ``mesh`` and which half-edges of ``mesh`` lie on the cut.
    """
    t = mesh.topology
    n = len(mesh.V)
    key = t.edges[:, 0] * n + t.edges[:, 1]
    on_cut = np.isin(key, cut[:, 0] * n + cut[:, 1]) if len(cut) else np.zeros(len(key), dtype=bool)
    is_cut_he = on_cut[t.corner_edge]
    # corners at the same vertex across a non-cut edge belong to the same wedge
    c = np.arange(len(t.corner_vertex))
    tw = t.twin
    join = (tw >= 0) & ~is_cut_he
    other = t.corner_next[np.maximum(tw, 0)]  # corner at this half-edge's start vertex in the twin face
    A = sp.coo_matrix((np.ones(join.sum()), (c[join], other[join])), shape=(len(c), len(c)))
    nw, wedge = connected_components(A, directed=False)
    # the half-edge leaving c starts at corner_vertex[c]; its twin leaves corner_next_vertex[c] and
    # ends at corner_vertex[c], so the twin's next corner sits at corner_vertex[c]: same vertex
    Vc = np.zeros((nw, 3))
    Vc[wedge] = mesh.V[t.corner_vertex]
    Fc = wedge.reshape(-1, 3)
    return Mesh(Vc, Fc, name=f"{mesh.name}-cut", check=False), wedge, is_cut_he


def transitions(mesh: Mesh, X1c: np.ndarray, is_cut_he: np.ndarray) -> np.ndarray:
    """(3t,) int quarter turns ``r`` per half-edge: the combed field of the twin face is ``M^r`` of this one's.

    0 off the cut and on the boundary.  X1c : (t, 3) combed field on the cut mesh.
    """
    t = mesh.topology
    nf = face_frames(mesh)[0]
    c = np.nonzero(is_cut_he & (t.twin >= 0))[0]
    f, g = c // 3, t.twin[c] // 3
    e = mesh.V[t.corner_next_vertex[c]] - mesh.V[t.corner_vertex[c]]
    e /= np.linalg.norm(e, axis=1, keepdims=True)
    af = _angle_to(e, X1c[f], nf[f])
    ag = _angle_to(e, X1c[g], nf[g])
    r = np.zeros(len(t.corner_vertex), dtype=np.int64)
    # X1_g = rot(+90 r) X1_f  <=>  (u, v)_g = M1^r (u, v)_f + t   (X2 = n x X1)
    r[c] = np.rint((ag - af) / (np.pi / 2)).astype(np.int64) % 4
    return r


def seamless_uv(cut_mesh: Mesh, G: sp.csr_matrix, area: np.ndarray, X1: np.ndarray, X2: np.ndarray,
                h: float, pairs: np.ndarray, rot: np.ndarray, group: np.ndarray,
                weight: float = 1e6, parity: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Integer-seamless ``UV (n_c, 2)`` on the cut mesh, and the integer translations ``(g, 2)``.

    G, area : gradient operator ``(3t, n_c)`` and areas of the cut mesh;
    X1, X2 : (t, 3) combed fields; pairs : (k, 2) cut-mesh vertices ``(a, b)``
    with ``uv[b] = M^rot uv[a] + t[group]``; rot : (k,) quarter turns;
    group : (k,) translation group of each pair (one per cut arc);
    parity : (k,) int, ``-1`` (free), ``0`` or ``1``: the wanted parity of
    ``t_u + t_v`` for the pair's group.  Under a quarter turn the fixed point
    ``(I - M)^-1 t`` is a lattice node when ``t_u + t_v`` is even and a cell
    centre when it is odd, so the parity of a singular vertex's group decides
    whether it becomes an irregular vertex or an irregular face.
    """
    nc = cut_mesh.n_vertices
    W = sp.diags(np.repeat(area, 3))
    K = G.T @ W @ G
    eps = 1e-9 * K.diagonal().mean()
    Kb = sp.block_diag([K, K]) + eps * sp.identity(2 * nc)
    rhs_x = np.concatenate([G.T @ W @ X1.ravel(), G.T @ W @ X2.ravel()]) / h
    ng = int(group.max()) + 1 if len(group) else 0
    k = len(pairs)
    Mr = rotation(rot)  # (k, 2, 2)
    # rows 2 i + c: uv[b, c] - sum_d M[c, d] uv[a, d] - t[group, c]
    rows, cols, vals = [], [], []
    for cc in range(2):
        rows.append(2 * np.arange(k) + cc)
        cols.append(cc * nc + pairs[:, 1])
        vals.append(np.ones(k))
        for dd in range(2):
            rows.append(2 * np.arange(k) + cc)
            cols.append(dd * nc + pairs[:, 0])
            vals.append(-Mr[:, cc, dd].astype(float))
    Cx = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(2 * k, 2 * nc))
    Ct = sp.csr_matrix((-np.ones(2 * k), (np.arange(2 * k), 2 * np.repeat(group, 2) + np.tile([0, 1], k))),
                       shape=(2 * k, 2 * ng))
    w = weight * K.diagonal().mean()

    def solve(Ct, fixed, tval):
        free = ~fixed
        C = sp.hstack([Cx, Ct[:, free]]).tocsc()
        A = sp.block_diag([Kb, 1e-9 * w * sp.identity(int(free.sum()))]) + w * (C.T @ C)
        b = np.concatenate([rhs_x, np.zeros(int(free.sum()))]) - w * (C.T @ (Ct[:, fixed] @ tval[fixed]))
        z = spla.spsolve(A.tocsc(), b)
        return z[:2 * nc], z[2 * nc:]

    x, tf = solve(Ct, np.zeros(2 * ng, dtype=bool), np.zeros(2 * ng))
    # groups: translations that agree (one cut arc), then greedy rounding, one group per pass
    key = np.round(np.concatenate([tf.reshape(-1, 2), rot_of_group(group, rot, ng)[:, None]], 1) * 1e3)
    _, grp = np.unique(key, axis=0, return_inverse=True)
    grp = grp.ravel()
    ng2 = int(grp.max()) + 1 if len(grp) else 0
    Ct = sp.csr_matrix((-np.ones(2 * k), (np.arange(2 * k), 2 * np.repeat(grp[group], 2) + np.tile([0, 1], k))),
                       shape=(2 * k, 2 * ng2))
    want = np.full(ng2, -1)
    if parity is not None:
        sel = parity >= 0
        want[grp[group[sel]]] = parity[sel]
    fixed = np.zeros(2 * ng2, dtype=bool)
    tval = np.zeros(2 * ng2)
    while not fixed.all():  # a handful of arcs: one rounding per pass
        x, tf = solve(Ct, fixed, tval)
        err = np.abs(tf - np.round(tf))
        j = int(np.argmin(err))
        idx = np.nonzero(~fixed)[0][j]
        g = idx // 2
        if want[g] < 0:
            tval[idx] = np.round(tf[j])
            fixed[idx] = True
            continue
        # a singular vertex's arc: both coordinates at once, the nearest integer pair of the wanted parity
        cur = np.full(2 * ng2, np.nan)
        cur[~fixed] = tf
        t2 = np.where(fixed[2 * g:2 * g + 2], tval[2 * g:2 * g + 2], cur[2 * g:2 * g + 2])
        cand = np.round(t2) + _STEPS
        ok = (cand.sum(1).astype(np.int64) % 2) == want[g]
        if fixed[2 * g] or fixed[2 * g + 1]:  # one coordinate already set: keep it
            keep = 0 if fixed[2 * g] else 1
            ok &= cand[:, keep] == t2[keep]
        best = cand[ok][np.argmin(np.linalg.norm(cand[ok] - t2, axis=1))]
        tval[2 * g:2 * g + 2] = best
        fixed[2 * g:2 * g + 2] = True
    x, _ = solve(Ct, fixed, tval)
    UV = np.stack([x[:nc], x[nc:]], 1)
    return UV, tval.reshape(-1, 2)


def rot_of_group(group: np.ndarray, rot: np.ndarray, ng: int) -> np.ndarray:
    """(ng,) quarter turns of every translation group (the rotation of its pairs)."""
    out = np.zeros(ng)
    out[group] = rot
    return out


def parametrize(mesh: Mesh, X1: np.ndarray, h: float, gradient, place: str = "nearest") -> dict:
    """The whole seamless chain on a triangle mesh with an uncombed per-triangle cross field ``X1 (t, 3)``.

    gradient : ``mesh -> (G (3t, n), area (t,))`` (:func:`optimize.remesh.quads.gradient_operator`).
    place : where singular vertices go: ``"nearest"`` (lattice node or cell
    centre, whichever the rounding gives), ``"faces"`` (cell centres: 3-/5-gons)
    or ``"vertices"`` (lattice nodes: valence-3/5 vertices).
    Returns a dict: ``UVc (t, 3, 2)`` per-corner parameters, ``rot (3t,)`` and
    ``shift (3t, 2)`` transitions into the twin face's chart, ``singular (s,)``
    vertices and their ``index (s,)`` (quarter turns), ``cut (c, 2)`` edges,
    ``mismatch`` (edges of the cut mesh where the combed field still jumps).
    """
    if place not in ("nearest", "faces", "vertices"):
        raise ValueError(f"place = {place!r}, expected 'nearest', 'faces' or 'vertices'")
    t = mesh.topology
    vi = vertex_indices(mesh, X1)
    singular = np.nonzero(vi)[0]
    cut = cut_graph(mesh, singular)
    cm, wedge, is_cut = cut_open(mesh, cut)
    X1c, mismatch = comb(cm, X1)
    nf = face_frames(mesh)[0]
    X2c = np.cross(nf, X1c)
    r = transitions(mesh, X1c, is_cut)
    c = np.nonzero(is_cut & (t.twin >= 0) & (np.arange(len(t.twin)) < np.maximum(t.twin, 0)))[0]
    tw = t.twin[c]
    pairs = np.concatenate([np.stack([wedge[c], wedge[t.corner_next[tw]]], 1),
                            np.stack([wedge[t.corner_next[c]], wedge[tw]], 1)])
    rot = np.concatenate([r[c], r[c]])
    group = np.concatenate([np.arange(len(c)), np.arange(len(c))])
    G, area = gradient(cm)
    parity = np.full(len(pairs), -1)
    if place != "nearest":  # the pairs of a singular vertex with itself: its own transition's fixed point
        parity[(pairs[:, 0] == pairs[:, 1]) & (rot % 2 == 1)] = 1 if place == "faces" else 0
    UV, _ = seamless_uv(cm, G, area, X1c, X2c, h, pairs, rot, group, parity=parity)
    # a singular vertex is the fixed point of its quarter turn: a lattice node or a cell centre, exactly
    # (the solve leaves it 1e-8 off, enough for a trace leaving the node to miss every triangle)
    fix = pairs[(pairs[:, 0] == pairs[:, 1]) & (rot % 2 == 1), 0]
    UV[fix] = np.round(2 * UV[fix]) / 2
    UVc = UV[cm.F]
    # transitions of every half-edge, from the solved parameters (integers by construction)
    he = np.nonzero(t.twin >= 0)[0]
    rot_he = np.zeros(len(t.twin), dtype=np.int64)
    shift = np.zeros((len(t.twin), 2))
    # half-edge c in f -> twin in g: r[c] for the side c < twin, the inverse turn for the other
    lo = he[he < t.twin[he]]
    rot_he[lo] = r[lo]
    rot_he[t.twin[lo]] = (-r[lo]) % 4
    M = rotation(rot_he[he]).astype(float)
    here = UV[wedge[he]]  # start vertex of the half-edge, in this face's chart
    there = UV[wedge[t.corner_next[t.twin[he]]]]  # the same vertex in the twin's chart
    shift[he] = np.round(there - np.einsum("kij,kj->ki", M, here))
    return {"UVc": UVc, "rot": rot_he, "shift": shift, "singular": singular, "index": vi[singular],
            "cut": cut, "mismatch": int(mismatch.sum()), "cut_mesh": cm}
