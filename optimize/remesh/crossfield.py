"""Cross fields on a triangle mesh: smoothing principal directions and combing them.

A cross (a direction field modulo quarter turns) at a vertex is stored as the
complex number ``z = exp(4 i theta)``, ``theta`` the angle of one of its arms
in the vertex frame ``(e1, e2)``.  Comparing crosses across an edge ``(i, j)``
uses the discrete connection ``rho_ij``: the angle, in ``i``'s frame, of ``j``'s
``e1`` projected on ``i``'s tangent plane.

- :func:`smooth_cross_field`: principal directions are undefined at umbilics
  and in flat regions and noisy near them.  One sparse Hermitian solve
  minimizes ``sum_edges |z_i - e^{4 i rho_ij} z_j|^2 + lam sum_i c_i |z_i - z0_i|^2``
  with ``c_i >= 0`` the confidence of the estimate (see
  :func:`optimize.remesh.quads.confidence`) and ``lam`` set by the smoothing
  length, so well-defined directions are kept and the rest is filled in
  smoothly over the smoothing length.
- :func:`face_crosses`: the per-triangle cross (mean of its vertices' crosses)
  and the singular triangles (cross-field index ``+-1/4``: umbilics of the field).
- :func:`comb`: choose one arm per triangle so that neighbours agree (a
  breadth-first sweep over the dual graph, one vectorized step per level).
  Around a singularity no choice agrees everywhere; the mismatch is left on
  the non-tree edges that circle it.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import breadth_first_order

from ..mesh import Mesh
from .principal import tangent_frames


def _rho(n_i, e1_i, e2_i, e1_j):
    """(k,) angle of ``e1_j`` projected on the planes ``n_i``, in the frames ``(e1_i, e2_i)``."""
    p = e1_j - np.einsum("ij,ij->i", e1_j, n_i)[:, None] * n_i
    return np.arctan2(np.einsum("ij,ij->i", p, e2_i), np.einsum("ij,ij->i", p, e1_i))


def smooth_cross_field(mesh: Mesh, normals: np.ndarray, dirs: np.ndarray, confidence: np.ndarray,
                       length: float) -> np.ndarray:
    """(n, 3) unit tangent vectors: one arm of the smoothed cross at every vertex.

    mesh : triangle Mesh; normals : (n, 3) unit vertex normals; dirs : (n, 3)
    tangent directions (principal); confidence : (n,) >= 0, 1 for a full
    estimate at a vertex (more where one estimate stands for several vertices,
    0 where there is none: filled in); length : smoothing length (model units;
    about the target edge length).
    """
    V, E = mesh.V, mesh.topology.edges
    n = len(V)
    e1, e2 = tangent_frames(normals)
    theta = np.arctan2(np.einsum("ij,ij->i", dirs, e2), np.einsum("ij,ij->i", dirs, e1))
    z0 = np.exp(4j * theta)
    i, j = E[:, 0], E[:, 1]
    rho_ij = _rho(normals[i], e1[i], e2[i], e1[j])  # j's frame seen from i
    h = np.linalg.norm(V[j] - V[i], axis=1).mean()
    lam = (h / max(length, h)) ** 2
    c = np.maximum(confidence, 0.0)
    if c.max() <= 1e-6:
        c = np.full(n, 1e-3)  # no reliable direction anywhere: keep the raw field, smoothed hard
    w = np.exp(4j * rho_ij)
    rows = np.concatenate([i, j, i, j, np.arange(n)])
    cols = np.concatenate([i, j, j, i, np.arange(n)])
    vals = np.concatenate([np.ones(len(i)), np.ones(len(i)), -w, -np.conj(w), lam * c])
    A = sp.csc_matrix((vals.astype(complex), (rows, cols)), shape=(n, n))
    z = spla.spsolve(A, lam * c * z0)
    ang = np.angle(z) / 4
    return np.cos(ang)[:, None] * e1 + np.sin(ang)[:, None] * e2


def face_frames(mesh: Mesh) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Unit face normals ``(t, 3)``, face frames ``e1, e2 (t, 3)`` and areas ``(t,)`` of a triangle mesh."""
    X = mesh.V[mesh.F]
    cr = np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])
    area = 0.5 * np.linalg.norm(cr, axis=1)
    nf = cr / np.maximum(2 * area, 1e-300)[:, None]
    e1 = X[:, 1] - X[:, 0]
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return nf, e1, np.cross(nf, e1), area


def face_crosses(mesh: Mesh, arms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-triangle cross and singular triangles.

    arms : (n, 3) one arm per vertex.  Returns ``X1 (t, 3)`` unit arm in each
    triangle's plane (not yet combed) and ``index (t,)`` in quarter turns
    (``0`` regular, ``+-1`` a singularity of index ``+-1/4``).
    """
    nf, e1, e2, _ = face_frames(mesh)
    F = mesh.F
    z = np.zeros(len(F), dtype=complex)
    ang = []
    for k in range(3):
        a = arms[F[:, k]] - np.einsum("ij,ij->i", arms[F[:, k]], nf)[:, None] * nf
        t = np.arctan2(np.einsum("ij,ij->i", a, e2), np.einsum("ij,ij->i", a, e1))
        ang.append(t)
        z += np.exp(4j * t)
    th = np.angle(z) / 4
    X1 = np.cos(th)[:, None] * e1 + np.sin(th)[:, None] * e2
    turn = sum(_wrap_quarter(ang[(k + 1) % 3] - ang[k]) for k in range(3))
    return X1, np.rint(turn / (np.pi / 2)).astype(np.int64)


def _wrap_quarter(d):
    """Angle difference modulo quarter turns, into ``(-pi/4, pi/4]``."""
    q = np.pi / 2
    return d - q * np.round(d / q)


def dual_graph(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Interior edges as face pairs ``(p, 2)`` and their edge indices ``(p,)``."""
    t = mesh.topology
    inner = np.nonzero(~t.is_boundary_edge)[0]
    return t.edge_faces[inner], inner


def comb(mesh: Mesh, X1: np.ndarray, root: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Combed arms ``(t, 3)``: ``X1`` turned by quarter turns so that neighbours agree.

    Returns ``(X1c (t, 3), mismatch (p,) bool)`` where ``mismatch`` flags the
    interior edges (in :func:`dual_graph` order) across which the combed arms
    still differ by a quarter turn or more (cuts from singularities).
    """
    nf, _, _, area = face_frames(mesh)
    pairs, _ = dual_graph(mesh)
    m = len(X1)
    G = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(m, m)).tocsr()
    G = G + G.T
    if root is None:
        c = (mesh.V[mesh.F].mean(1) * area[:, None]).sum(0) / area.sum()
        root = int(np.argmin(np.linalg.norm(mesh.V[mesh.F].mean(1) - c, axis=1)))
    order, pred = breadth_first_order(G, root, directed=False)
    # depth in the BFS tree by pointer jumping (log(depth) vectorized steps)
    anc = np.where(pred >= 0, pred, np.arange(m))
    depth = (pred >= 0).astype(np.int64)
    while np.any(anc != anc[anc]):
        depth, anc = depth + depth[anc], anc[anc]
    out = X1.copy()
    for level in range(1, int(depth.max()) + 1):  # one vectorized step per BFS level
        f = np.nonzero(depth == level)[0]
        p = pred[f]
        ref = out[p] - np.einsum("ij,ij->i", out[p], nf[f])[:, None] * nf[f]
        a, b = out[f], np.cross(nf[f], out[f])
        ca, cb = np.einsum("ij,ij->i", a, ref), np.einsum("ij,ij->i", b, ref)
        best = np.argmax(np.stack([ca, cb, -ca, -cb], 1), axis=1)
        out[f] = np.where((best == 0)[:, None], a, np.where((best == 1)[:, None], b,
                                                            np.where((best == 2)[:, None], -a, -b)))
    p0, p1 = pairs[:, 0], pairs[:, 1]
    ref = out[p0] - np.einsum("ij,ij->i", out[p0], nf[p1])[:, None] * nf[p1]
    ref /= np.maximum(np.linalg.norm(ref, axis=1, keepdims=True), 1e-300)
    mismatch = np.einsum("ij,ij->i", ref, out[p1]) < np.cos(np.pi / 4)
    return out, mismatch
