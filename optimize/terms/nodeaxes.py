"""Node axes as unknowns: every node conical, every beam planar.

For the vertex formulation of the conical target (``formulation``, option
``torsion_free_beams``).  Every vertex ``v`` (boundary ones too: there the
faces leave the axis partly free, and the beams to the boundary must be
planar as well) gets a unit axis ``a_v`` and ``c_v = cos(theta_v)`` with

- cone rows ``n_f . a_v - c_v = 0`` for the faces ``f`` around ``v``, any
  valence (the face planes touch one cone of revolution; at valence 4 this
  is the angle balance, at valence 5 and more it is not implied by anything
  else), with ``n_f = N_f / |N_f|`` the unit Newell normal computed from the
  positions: with ``b = (a - (a.n) n) / (2 |N|)`` the gradient of ``n . a``
  with respect to vertex ``j`` of the face is ``(v_(j+1) - v_(j-1)) x b``;
- beam rows ``(e x a_v) . a_w / |e| = 0`` for every edge ``e = w - v``: the
  edge and both node axes in one plane, so the support beam between two
  layers is a planar quadrilateral.

Why the beam rows: two neighbouring cones' axes lie in a bisector plane of
the two faces at their edge only while those faces are not coplanar.  On
``halftunnel.off`` the conical solve made faces around its valence-5
vertices coplanar (the easy way to put five planes on one cone), the
least-squares axes of the offset stage then twisted beams by 29 mm; with
these rows and the solver's own axes every beam is planar to 3e-9 m (the
run takes about 66 iterations, 5 s, against 12 without: the axes of
nearly coplanar faces converge slowly).  With axes on interior vertices only,
the beams from the boundary twisted by 25 mm: the offset stage could not turn
the boundary axes to match the fixed interior ones.

Blocks: ``vertices (n, 3)``, ``node_axes (p, 3)``, ``node_cos (p,)`` for the
vertices :func:`axis_vertices` (in that order).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from ..mesh.measures import _vector_areas, face_normals
from .variables import Layout


def axis_vertices(mesh: Mesh, boundary: bool = True) -> np.ndarray:
    """(p,) int: the vertices with a node axis: every vertex (``boundary``), else the interior ones."""
    t = mesh.topology
    keep = (t.star_size >= 1) if boundary else (~t.is_boundary_vertex & (t.star_size >= 3))
    return np.nonzero(keep)[0]


def beam_edges(mesh: Mesh, boundary: bool = True) -> np.ndarray:
    """(k, 2) int: every edge (``boundary``), else the edges whose two ends are interior."""
    t = mesh.topology
    E = t.edges
    return E if boundary else E[~t.is_boundary_vertex[E[:, 0]] & ~t.is_boundary_vertex[E[:, 1]]]


def _pairs(mesh: Mesh, cv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(owner (r,), face (r,))``: position in ``cv`` and face of every cone row."""
    S = mesh.topology.star_faces[cv]
    owner, slot = np.nonzero(S >= 0)
    return owner, S[owner, slot]


def _corner_spans(mesh: Mesh, V: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``w = v_(j+1) - v_(j-1)`` ``(r, k, 3)`` at every corner of ``faces (r,)`` (zero in padded
    slots): the derivative of a face's vector area by its corner ``j`` is ``w_j x / 2``."""
    F = mesh.F[faces]
    valid = F >= 0
    size = valid.sum(axis=1)
    j = np.arange(F.shape[1])[None, :]
    nxt = np.take_along_axis(F, (j + 1) % size[:, None], axis=1)
    prv = np.take_along_axis(F, (j - 1) % size[:, None], axis=1)
    return np.where(valid[..., None], V[np.maximum(nxt, 0)] - V[np.maximum(prv, 0)], 0.0)


def cone_terms(x: np.ndarray, layout: Layout, mesh: Mesh, cv: np.ndarray, jacobian: bool = True):
    """Cone rows: residual ``(r,)`` and Jacobian ``(r, layout.size)`` (None with ``jacobian=False``)
    for the vertices ``cv``."""
    owner, faces = _pairs(mesh, cv)
    V = layout.view(x, "vertices")
    A, c = layout.view(x, "node_axes"), layout.view(x, "node_cos")
    N = 0.5 * _vector_areas(mesh, V)[faces]  # each face once, then one row per (vertex, face)
    length = np.maximum(np.linalg.norm(N, axis=1), 1e-300)
    n = N / length[:, None]
    a = A[owner]
    r = np.einsum("ij,ij->i", n, a) - c[owner]
    if not jacobian:
        return r, None
    w = _corner_spans(mesh, V, faces)
    b = (a - np.einsum("ij,ij->i", a, n)[:, None] * n) / (2.0 * length[:, None])
    gv = np.cross(w, b[:, None, :])  # (r, k, 3)
    F = mesh.F[faces]
    valid = np.broadcast_to((F >= 0)[..., None], gv.shape)
    rows_v = np.broadcast_to(np.arange(len(r))[:, None, None], gv.shape)
    cols_v = layout.index("vertices")[np.maximum(F, 0)]
    ia, ic = layout.index("node_axes"), layout.index("node_cos")
    rows = np.concatenate([rows_v[valid], np.repeat(np.arange(len(r)), 4)])
    cols = np.concatenate([cols_v[valid], np.concatenate([ia[owner], ic[owner][:, None]], axis=1).ravel()])
    vals = np.concatenate([gv[valid], np.concatenate([n, -np.ones((len(r), 1))], axis=1).ravel()])
    return r, sp.csr_matrix((vals, (rows, cols)), shape=(len(r), layout.size))


def beam_terms(x: np.ndarray, layout: Layout, E: np.ndarray, pos: np.ndarray, jacobian: bool = True):
    """Beam rows for edges ``E (k, 2)``; ``pos (n,)`` maps a vertex to its row of ``node_axes``.
    Residual ``(k,)`` and Jacobian (None with ``jacobian=False``)."""
    V, A = layout.view(x, "vertices"), layout.view(x, "node_axes")
    v, w = E[:, 0], E[:, 1]
    e = V[w] - V[v]
    L = np.maximum(np.linalg.norm(e, axis=1), 1e-300)[:, None]
    av, aw = A[pos[v]], A[pos[w]]
    r = np.einsum("ij,ij->i", np.cross(e, av), aw) / L[:, 0]
    if not jacobian:
        return r, None
    ge = np.cross(av, aw) / L - (r[:, None] * e) / L ** 2
    iv, ia = layout.index("vertices"), layout.index("node_axes")
    cols = np.concatenate([iv[w], iv[v], ia[pos[v]], ia[pos[w]]], axis=1)
    vals = np.concatenate([ge, -ge, np.cross(aw, e) / L, np.cross(e, av) / L], axis=1)
    rows = np.repeat(np.arange(len(E)), 12)
    return r, sp.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(len(E), layout.size))


def start(mesh: Mesh, V: np.ndarray, cv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starting axes ``(p, 3)`` and cosines ``(p,)``: least squares ``N X = 1`` over the unit
    face normals at each vertex (regularized), ``a = X / |X|``, ``c`` the mean ``n . a``."""
    owner, faces = _pairs(mesh, cv)
    n = face_normals(mesh, V)[faces]  # unit
    M = np.zeros((len(cv), 3, 3))
    rhs = np.zeros((len(cv), 3))
    np.add.at(M, owner, np.einsum("ri,rj->rij", n, n))
    np.add.at(rhs, owner, n)
    X = np.linalg.solve(M + 1e-9 * np.eye(3), rhs[..., None])[..., 0]
    a = X / np.maximum(np.linalg.norm(X, axis=1), 1e-300)[:, None]
    k = np.maximum(np.bincount(owner, minlength=len(cv)), 1)
    cos = np.bincount(owner, weights=np.einsum("ri,ri->r", n, a[owner]), minlength=len(cv)) / k
    return a, cos
