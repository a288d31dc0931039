"""Convexity: a corner that starts convex stays convex (a one-sided row per corner).

A planar quad can meet every planarity row and still be dented (a reflex
corner) or a bow-tie: planar but not cuttable from glass.  The paper's
angle-sum condition ``phi1 + ... + phi4 = 2 pi`` means planar *and* convex;
the diagonal-distance and unit-normal rows of ``formulation`` only mean
planar.  This row keeps the signed sine of each corner angle about its
face's unit Newell normal,

    s_c = ((q - p) x (r - p)) . n_f / (|q - p| |r - p|),

(``p`` the corner's vertex, ``q`` the next and ``r`` the previous vertex of
its face; positive at a convex corner, negative at a reflex one: the measure
of ``measures.corner_turns``) above a floor: the hinge ``min(0, s_c - floor)``,
zero while the corner is convex enough, so it acts only on corners about to
turn reflex and its square is continuously differentiable (like
``terms.edgefloor``).  A polygon whose corners all have a positive sine
about its normal is convex, so the rows of a face's corners together say
"convex".  The floor (:func:`floors`) is ``min(SINE_FLOOR, s0 / 2)`` of the
start sine ``s0``: a corner of 90 degrees may open to about 174 or close to
6 degrees, one that starts at 178 degrees keeps half its margin.

Gradient: with ``c = u x w``, ``u = q - p``, ``w = r - p``, ``N`` the vector
area and ``b = (I - n n^T) c / |N|`` (the change of ``c . n`` through the
normal), ``ds/dq = (w x n) / (|u||w|) - s u / |u|^2``, ``ds/dr = (n x u) /
(|u||w|) - s w / |w|^2``, ``ds/dp = -(ds/dq + ds/dr)`` and every vertex ``j``
of the face adds ``(w_j x b) / (2 |u||w|)`` with ``w_j = v_(j+1) - v_(j-1)``
(``dN/dv_j = w_j x / 2``).  Each row stays within one face.

The paper's angle-sum rows ``phi1 + ... + phi4 = 2 pi`` (planar and convex)
beside these were measured not to help (hypar900 / wave900 stalled the same,
conjugate900+noise 7 -> 10 iterations), so they are not added.

Block: ``vertices (n, 3)``.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from ..mesh.measures import COLLAPSED, corner_turns
from ..tolerances import DEFAULT
from .nodeaxes import _corner_spans
from .variables import Layout

SINE_FLOOR = 0.1  # about 5.7 degrees from straight or from closed


def vector_areas(mesh: Mesh, V: np.ndarray) -> np.ndarray:
    """(m, 3) float: twice the vector area of each face (as ``measures._vector_areas``, summed
    with ``bincount``: the rows are evaluated at every trial step)."""
    t = mesh.topology
    o = V[mesh.F[t.corner_face, 0]]
    cr = np.cross(V[t.corner_vertex] - o, V[t.corner_next_vertex] - o)
    return np.stack([np.bincount(t.corner_face, weights=cr[:, k], minlength=mesh.n_faces) for k in range(3)],
                    axis=1)


def turns(mesh: Mesh, V: np.ndarray, corners: np.ndarray | None = None,
          areas: np.ndarray | None = None) -> np.ndarray:
    """Signed corner sines (``measures.corner_turns``) of ``corners`` (default all) at ``V (n, 3)``."""
    t = mesh.topology
    c = slice(None) if corners is None else corners
    A = vector_areas(mesh, V) if areas is None else areas
    N = A / np.maximum(np.linalg.norm(A, axis=1, keepdims=True), 1e-300)
    P = V[t.corner_vertex[c]]
    u, w = V[t.corner_next_vertex[c]] - P, V[t.corner_prev_vertex[c]] - P
    lengths = np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1), 1e-300)
    return np.einsum("ij,ij->i", np.cross(u, w), N[t.corner_face[c]]) / lengths


class FoldCheck:
    """``measures.folded_faces`` against fixed start positions ``V0 (n, 3)``, with what depends on
    ``V0`` computed once (the optimizer asks at every trial step)."""

    def __init__(self, mesh: Mesh, V0: np.ndarray, tol: float = DEFAULT.fold):
        t = mesh.topology
        self.mesh, self.tol = mesh, tol
        A0 = vector_areas(mesh, V0)
        self.N0 = A0 / np.maximum(np.linalg.norm(A0, axis=1, keepdims=True), 1e-300)
        self.convex0 = turns(mesh, V0, areas=A0) > -tol
        self.l0 = np.linalg.norm(V0[t.corner_next_vertex] - V0[t.corner_vertex], axis=1)

    def faces(self, V: np.ndarray) -> np.ndarray:
        """(m,) bool: faces folded at ``V`` (reflex where convex at the start, flipped, collapsed)."""
        t, m = self.mesh.topology, self.mesh.n_faces
        A = vector_areas(self.mesh, V)
        bad_corner = self.convex0 & (turns(self.mesh, V, areas=A) < -self.tol)
        l1 = np.linalg.norm(V[t.corner_next_vertex] - V[t.corner_vertex], axis=1)
        bad_corner |= l1 < COLLAPSED * self.l0
        bad = np.bincount(t.corner_face, weights=bad_corner, minlength=m) > 0
        return bad | (np.einsum("ij,ij->i", self.N0, A) < 0)


def floors(mesh: Mesh, V: np.ndarray, fold: float = DEFAULT.fold) -> tuple[np.ndarray, np.ndarray]:
    """``(corners (k,), floor (k,))``: the corners convex at positions ``V (n, 3)`` (start sine
    above ``-fold``, ``Tolerances.fold``, as ``measures.folded_faces``) and their floors."""
    s0 = corner_turns(mesh, V)
    corners = np.nonzero(s0 > -fold)[0]
    return corners, np.minimum(SINE_FLOOR, 0.5 * np.maximum(s0[corners], 0.0))


def sines(mesh: Mesh, V: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(k,) float: the signed corner sines ``s_c`` of ``corners`` at positions ``V (n, 3)``."""
    return turns(mesh, V, corners)


def terms(x: np.ndarray, layout: Layout, mesh: Mesh, corners: np.ndarray,
          floor: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual ``(k,)`` and Jacobian ``(k, layout.size)`` of the hinge rows of ``corners``.

    Rows of corners at or above their floor are zero, with a zero Jacobian row.
    """
    t = mesh.topology
    V = layout.view(x, "vertices")
    areas = vector_areas(mesh, V)
    s = turns(mesh, V, corners, areas)
    low = np.nonzero(s < floor)[0]
    r = np.where(s < floor, s - floor, 0.0)
    idx = layout.index("vertices")
    if not len(low):
        return r, sp.csr_matrix((len(corners), layout.size))
    c = corners[low]
    f = t.corner_face[c]
    p, q, rr = t.corner_vertex[c], t.corner_next_vertex[c], t.corner_prev_vertex[c]
    u, w = V[q] - V[p], V[rr] - V[p]
    lu, lw = np.linalg.norm(u, axis=1), np.linalg.norm(w, axis=1)
    den = np.maximum(lu * lw, 1e-300)[:, None]
    N = 0.5 * areas[f]
    ln = np.maximum(np.linalg.norm(N, axis=1), 1e-300)[:, None]
    n = N / ln
    cr = np.cross(u, w)
    sv = s[low][:, None]
    gq = np.cross(w, n) / den - sv * u / np.maximum(lu, 1e-300)[:, None] ** 2
    gr = np.cross(n, u) / den - sv * w / np.maximum(lw, 1e-300)[:, None] ** 2
    b = (cr - np.einsum("ij,ij->i", cr, n)[:, None] * n) / ln
    gv = np.cross(_corner_spans(mesh, V, f), b[:, None, :]) / (2.0 * den[:, :, None])  # (a, k, 3)
    F = mesh.F[f]
    valid = np.broadcast_to((F >= 0)[..., None], gv.shape)
    rows_v = np.broadcast_to(low[:, None, None], gv.shape)
    cols_v = idx[np.maximum(F, 0)]
    rows = np.concatenate([rows_v[valid], np.repeat(low, 9)])
    cols = np.concatenate([cols_v[valid], np.concatenate([idx[q], idx[rr], idx[p]], axis=1).ravel()])
    vals = np.concatenate([gv[valid], np.concatenate([gq, gr, -(gq + gr)], axis=1).ravel()])
    return r, sp.csr_matrix((vals, (rows, cols)), shape=(len(corners), layout.size))
