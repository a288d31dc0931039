"""Catmull-Clark and Doo-Sabin subdivision as sparse linear operators.

Each scheme returns the refined mesh and the operator ``S`` with
``V_fine = S @ V_coarse`` (``S : (n_fine, n_coarse)`` scipy CSR, every row a
convex combination: rows sum to one, entries non-negative).  The fine faces
depend only on the coarse faces, so ``S`` can be reused for any positions on
the same connectivity (the modelling loop subdivides a perturbed mesh with
the same ``S``).  Operators are assembled from COO triplets over all corners
at once; there is no loop over faces or vertices.

Catmull-Clark (any polygon mesh; the result is all quads)
    fine vertex order: ``[vertex points (n), edge points (e), face points (m)]``,
    so coarse vertex ``i`` is fine vertex ``i`` and edge ``j`` of
    ``mesh.topology.edges`` gives fine vertex ``n + j``.
    Boundary and crease rules are those of OpenSubdiv with "edge and corner"
    boundary interpolation (Blender's "keep corners", Rhino SubD):
    boundary and crease edges get midpoints, a vertex on exactly two sharp
    edges gets ``3/4 v + 1/8 (a + b)``, so each boundary curve is refined by
    the cubic B-spline rule; boundary vertices with one face (valence 2),
    vertices on three or more sharp edges and user ``corners`` stay put.

Doo-Sabin (any polygon mesh; F-, E- and V-faces)
    fine vertex order: ``[corner points (c), boundary points (2 b), corners (k)]``:
    one point per corner of the coarse mesh (``topology`` corner order, the
    classic weights ``(k + 5) / 4k`` and ``(3 + 2 cos(2 pi j / k)) / 4k``),
    two per boundary edge (``3/4 a + 1/4 b`` and ``1/4 a + 3/4 b``: the
    boundary polygon is refined by Chaikin's rule, its limit the quadratic
    B-spline of the coarse boundary), and the boundary corners (boundary
    vertices with one face) kept as vertices.  On a quad grid the result is
    again a quad grid.
"""
from __future__ import annotations

import logging

import numpy as np
import scipy.sparse as sp

from ..errors import ConfigError, MeshError
from ..mesh import Mesh

log = logging.getLogger(__name__)

__all__ = ["catmull_clark", "doo_sabin", "chaikin", "lane_riesenfeld", "subdivide", "SCHEMES"]


def _coo(vals, rows, cols, shape) -> sp.csr_matrix:
    """CSR matrix from triplets (duplicates summed)."""
    return sp.csr_matrix((np.asarray(vals, dtype=float), (rows, cols)), shape=shape)


def _edge_index(mesh: Mesh, pairs: np.ndarray, what: str) -> np.ndarray:
    """(k,) int: indices in ``topology.edges`` of vertex pairs ``(k, 2)``; MeshError if not edges."""
    t = mesh.topology
    n = mesh.n_vertices
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    if pairs.size and (pairs.min() < 0 or pairs.max() >= n):
        raise MeshError(f"{mesh.name}: {what} refer to vertex outside 0..{n - 1}: {pairs.tolist()[:5]}")
    key = np.minimum(pairs[:, 0], pairs[:, 1]) * n + np.maximum(pairs[:, 0], pairs[:, 1])
    keys = t.edges[:, 0] * n + t.edges[:, 1]
    idx = np.minimum(np.searchsorted(keys, key), len(keys) - 1)
    bad = keys[idx] != key
    if bad.any():
        raise MeshError(f"{mesh.name}: {what} {pairs[bad][0].tolist()} is not an edge of the mesh "
                        f"({int(bad.sum())} such pair(s)), expected pairs of adjacent vertices")
    return idx


# -- Catmull-Clark --------------------------------------------------------------

def _catmull_clark_once(mesh: Mesh, crease: np.ndarray, corner: np.ndarray):
    """One Catmull-Clark step.

    crease : (e,) bool, user crease edges (boundary edges are sharp anyway).
    corner : (n,) bool, user corner vertices.
    Returns (fine Mesh, S (n_fine, n) CSR, fine crease (e_fine,) bool, fine corner (n_fine,) bool).
    """
    t = mesh.topology
    n, m, ne = mesh.n_vertices, mesh.n_faces, len(t.edges)
    cf, cv, cn = t.corner_face, t.corner_vertex, t.corner_next_vertex
    k_c = t.face_sizes[cf].astype(float)
    # face points: centroids
    Sf = _coo(1.0 / k_c, cf, cv, (m, n))
    # edge points: midpoint on sharp edges, (a + b + f0 + f1) / 4 on smooth ones
    sharp = crease | t.is_boundary_edge
    ea, eb = t.edges[:, 0], t.edges[:, 1]
    w = np.where(sharp, 0.5, 0.25)
    ei = np.arange(ne)
    Ev = _coo(np.concatenate([w, w]), np.concatenate([ei, ei]), np.concatenate([ea, eb]), (ne, n))
    sm = np.nonzero(~sharp)[0]
    Ef = _coo(np.full(2 * len(sm), 0.25), np.repeat(sm, 2), t.edge_faces[sm].ravel(), (ne, m))
    Se = Ev + Ef @ Sf
    # vertex points: rule by the number of sharp edges at the vertex
    n_sharp = np.bincount(t.edges[sharp].ravel(), minlength=n)
    is_corner = corner | (n_sharp > 2) | (t.is_boundary_vertex & (t.star_size == 1))
    is_crease = ~is_corner & (n_sharp == 2)
    smooth = ~is_corner & ~is_crease
    k_v = t.star_size.astype(float)
    diag = np.where(is_corner, 1.0, np.where(is_crease, 0.75, (k_v - 2.0) / k_v))
    sel = smooth[cv]  # corners at smooth vertices: one per incident face and edge
    kk = k_v[cv[sel]]
    Cf = _coo(1.0 / kk ** 2, cv[sel], cf[sel], (n, m))
    sa, sb = ea[sharp], eb[sharp]
    ca, cb = is_crease[sa], is_crease[sb]
    rows = np.concatenate([np.arange(n), cv[sel], sa[ca], sb[cb]])
    cols = np.concatenate([np.arange(n), cn[sel], sb[ca], sa[cb]])
    vals = np.concatenate([diag, 1.0 / kk ** 2, np.full(ca.sum(), 0.125), np.full(cb.sum(), 0.125)])
    Sv = _coo(vals, rows, cols, (n, n)) + Cf @ Sf
    S = sp.vstack([Sv, Se, Sf], format="csr")
    # fine faces: one quad per corner (vertex, next edge point, face point, previous edge point)
    F = np.stack([cv, n + t.corner_edge, n + ne + cf, n + t.corner_edge[t.corner_prev]], axis=1)
    fine = Mesh(S @ mesh.V, F, name=mesh.name)
    # sharp user creases split in two halves; user corners keep their index
    ce = np.nonzero(crease)[0]
    crease_pairs = np.concatenate([np.stack([ea[ce], n + ce], axis=1), np.stack([n + ce, eb[ce]], axis=1)])
    fine_crease = np.zeros(len(fine.topology.edges), dtype=bool)
    if len(ce):
        fine_crease[_edge_index(fine, crease_pairs, "crease")] = True
    fine_corner = np.zeros(fine.n_vertices, dtype=bool)
    fine_corner[:n] = corner
    return fine, S, fine_crease, fine_corner


def catmull_clark(mesh: Mesh, levels: int = 1, *, creases=None, corners=None) -> tuple[Mesh, sp.csr_matrix]:
    """Catmull-Clark subdivision, ``levels`` times.

    Parameters
    ----------
    mesh : Mesh
        Any polygon mesh (boundaries allowed; the result is all quads).
    levels : int, >= 0
    creases : (k, 2) int or None
        Vertex pairs of edges to keep sharp (infinitely sharp creases, refined
        like boundary curves).
    corners : (j,) int or None
        Vertex indices kept in place (boundary valence-2 vertices are corners
        anyway).

    Returns
    -------
    fine : Mesh
        The refined mesh (named like the input).
    S : (n_fine, n) scipy.sparse CSR
        ``fine.V == S @ mesh.V``; rows sum to one.
    """
    levels = _check_levels(levels)
    n = mesh.n_vertices
    crease = np.zeros(len(mesh.topology.edges), dtype=bool)
    if creases is not None and np.size(creases):
        crease[_edge_index(mesh, creases, "crease")] = True
    corner = np.zeros(n, dtype=bool)
    if corners is not None and np.size(corners):
        c = np.asarray(corners, dtype=np.int64).ravel()
        if c.min() < 0 or c.max() >= n:
            raise MeshError(f"{mesh.name}: corner vertex {int(c[(c < 0) | (c >= n)][0])} "
                            f"is outside 0..{n - 1}")
        corner[c] = True
    S = sp.identity(n, format="csr")
    fine = mesh
    for _ in range(levels):
        fine, S1, crease, corner = _catmull_clark_once(fine, crease, corner)
        S = (S1 @ S).tocsr()
    log.info("catmull_clark %s: %d -> %d vertices in %d level(s)", mesh.name, n, fine.n_vertices, levels)
    return fine, S


# -- Doo-Sabin --------------------------------------------------------------------

def _doo_sabin_once(mesh: Mesh):
    """One Doo-Sabin step; returns (fine Mesh, S (n_fine, n) CSR)."""
    t = mesh.topology
    n = mesh.n_vertices
    cf, cv = t.corner_face, t.corner_vertex
    nc = len(cv)
    size = t.face_sizes[cf]
    local = np.arange(nc) - t.offsets[cf]
    # every corner c weighs every corner of its face at cyclic distance j
    rows = np.repeat(np.arange(nc), size)
    j = np.arange(len(rows)) - np.repeat(np.cumsum(size) - size, size)
    k = size[rows].astype(float)
    other = t.offsets[cf[rows]] + (local[rows] + j) % size[rows]
    w = np.where(j == 0, (k + 5.0) / (4.0 * k), (3.0 + 2.0 * np.cos(2.0 * np.pi * j / k)) / (4.0 * k))
    Sc = _coo(w, rows, cv[other], (nc, n))
    # boundary edges: two Chaikin points each, on the half-edge direction a -> b of its face
    be = np.nonzero(t.is_boundary_edge)[0]
    nb = len(be)
    c0 = t.edge_corners[be, 0]
    a, b = cv[c0], t.corner_next_vertex[c0]
    bi = np.arange(nb)
    Sb = _coo(np.tile([0.75, 0.25, 0.25, 0.75], nb),
              np.stack([2 * bi, 2 * bi, 2 * bi + 1, 2 * bi + 1], axis=1).ravel(),
              np.stack([a, b, a, b], axis=1).ravel(), (2 * nb, n))
    corner_v = np.nonzero(t.is_boundary_vertex & (t.star_size == 1))[0]
    Sk = _coo(np.ones(len(corner_v)), np.arange(len(corner_v)), corner_v, (len(corner_v), n))
    S = sp.vstack([Sc, Sb, Sk], format="csr")
    b_base, k_base = nc, nc + 2 * nb
    bpos = np.full(len(t.edges), -1, dtype=np.int64)
    bpos[be] = bi
    faces = []
    # F-faces: the corner points of each face
    kmax = int(t.face_sizes.max())
    FF = np.full((mesh.n_faces, kmax), -1, dtype=np.int64)
    FF[cf, local] = np.arange(nc)
    faces.append(FF)
    # E-faces of interior edges: [c at a, twin-face corner at a, twin-face corner at b, c at b]
    ie = np.nonzero(~t.is_boundary_edge)[0]
    c, d = t.edge_corners[ie, 0], t.edge_corners[ie, 1]
    va, vb = cv[c], t.corner_next_vertex[c]
    da = np.where(cv[d] == va, d, t.corner_next[d])
    db = np.where(cv[d] == vb, d, t.corner_next[d])
    faces.append(np.stack([c, da, db, t.corner_next[c]], axis=1))
    # E-faces of boundary edges: [a-side point, b-side point, corner at b, corner at a]
    faces.append(np.stack([b_base + 2 * bi, b_base + 2 * bi + 1, t.corner_next[c0], c0], axis=1))
    # V-faces: the corner points around each vertex in star order, closed on the boundary
    s = t.star_size
    smax = int(s.max())
    inner = np.nonzero(~t.is_boundary_vertex)[0]
    faces.append(t.star_corners[inner, :smax])
    bv = np.nonzero(t.is_boundary_vertex)[0]
    sb = s[bv]
    first = t.star_corners[bv, 0]
    last = t.star_corners[bv, sb - 1]
    e_first = np.where(t.is_boundary_edge[t.corner_edge[first]], t.corner_edge[first],
                       t.corner_edge[t.corner_prev[first]])
    e_last = np.where(t.is_boundary_edge[t.corner_edge[t.corner_prev[last]]],
                      t.corner_edge[t.corner_prev[last]], t.corner_edge[last])
    e_first = np.where(sb == 1, t.corner_edge[first], e_first)
    e_last = np.where(sb == 1, t.corner_edge[t.corner_prev[last]], e_last)

    def near(e, v):  # the boundary point of edge e next to vertex v
        return b_base + 2 * bpos[e] + (a[bpos[e]] != v)

    BF = np.full((len(bv), smax + 3), -1, dtype=np.int64)
    BF[:, :smax] = t.star_corners[bv, :smax]
    r = np.arange(len(bv))
    is_k = sb == 1
    kidx = np.full(n, -1, dtype=np.int64)
    kidx[corner_v] = k_base + np.arange(len(corner_v))
    BF[r, sb] = near(e_last, bv)
    BF[r[is_k], sb[is_k] + 1] = kidx[bv[is_k]]
    BF[r, sb + 1 + is_k] = near(e_first, bv)
    faces.append(BF)
    width = max(f.shape[1] for f in faces)
    F = np.concatenate([np.pad(f, ((0, 0), (0, width - f.shape[1])), constant_values=-1) for f in faces])
    F = F[:, (F >= 0).any(axis=0)]
    fine = Mesh(S @ mesh.V, F, name=mesh.name)
    return fine, S


def doo_sabin(mesh: Mesh, levels: int = 1) -> tuple[Mesh, sp.csr_matrix]:
    """Doo-Sabin subdivision, ``levels`` times.

    Parameters
    ----------
    mesh : Mesh
        Any polygon mesh (boundaries allowed).
    levels : int, >= 0

    Returns
    -------
    fine : Mesh
        F-faces (one per coarse face), E-faces (quads, one per edge),
        V-faces (one per vertex; ``valence``-gons inside, closed by the
        boundary points on the boundary).
    S : (n_fine, n) scipy.sparse CSR
        ``fine.V == S @ mesh.V``; rows sum to one.
    """
    levels = _check_levels(levels)
    S = sp.identity(mesh.n_vertices, format="csr")
    fine = mesh
    for _ in range(levels):
        fine, S1 = _doo_sabin_once(fine)
        S = (S1 @ S).tocsr()
    log.info("doo_sabin %s: %d -> %d vertices in %d level(s)", mesh.name, mesh.n_vertices,
             fine.n_vertices, levels)
    return fine, S


def chaikin(mesh: Mesh, levels: int = 1) -> tuple[Mesh, sp.csr_matrix]:
    """Strip meshes only: both boundary polylines refined by Chaikin's rule
    (:func:`optimize.modelling.strips.refine_strips`); returns ``(fine, S)``."""
    from .strips import refine_strips

    return refine_strips(mesh, "chaikin", _check_levels(levels))


def lane_riesenfeld(mesh: Mesh, levels: int = 1) -> tuple[Mesh, sp.csr_matrix]:
    """Strip meshes only: both boundary polylines refined by the cubic
    Lane-Riesenfeld rule (:func:`optimize.modelling.strips.refine_strips`); returns ``(fine, S)``."""
    from .strips import refine_strips

    return refine_strips(mesh, "lane_riesenfeld", _check_levels(levels))


SCHEMES = {"catmull_clark": catmull_clark, "doo_sabin": doo_sabin, "chaikin": chaikin,
           "lane_riesenfeld": lane_riesenfeld}
"""Scheme name -> function ``(mesh, levels) -> (fine, S)``; the last two refine strip meshes."""


def subdivide(mesh: Mesh, scheme: str = "catmull_clark", levels: int = 1) -> tuple[Mesh, sp.csr_matrix]:
    """Dispatch by name: ``scheme`` in :data:`SCHEMES`; returns ``(fine, S)``."""
    if scheme not in SCHEMES:
        raise ConfigError(f"subdivision scheme {scheme!r} is unknown, expected one of {sorted(SCHEMES)}")
    return SCHEMES[scheme](mesh, levels)


def _check_levels(levels) -> int:
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or levels < 0:
        raise ConfigError(f"subdivision levels is {levels!r}, expected an integer >= 0")
    return int(levels)
