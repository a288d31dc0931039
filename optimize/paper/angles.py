"""Corner angles and their exact Jacobians with respect to the vertex positions.

Every angle constraint of the paper (angle sum per face, the conical angle
balance per vertex, the circular angle pairs per quad) is a signed sum of
corner angles plus a constant.  This module computes, for every corner ``c``
of the mesh (``topology`` corner order), the angle

    phi_c = angle(u, w),  u = V[next] - V[p],  w = V[prev] - V[p],  p = V[corner_vertex]

with ``phi = atan2(|u x w|, u . w)`` (accurate near 0 and pi), its gradient with
respect to the three vertices involved, and assembles signed sums of angles
into a residual vector and a sparse Jacobian in one call (:func:`combine`).

Gradients (``nrm = u x w``)::

    d phi / d u = (u x nrm) / (|u|^2 |nrm|)      d phi / d w = (nrm x w) / (|w|^2 |nrm|)
    d phi / d p = -(d phi / d u + d phi / d w)

At a degenerate corner (``u`` parallel to ``w``) the angle is not
differentiable; the gradient returned there is zero.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..topology import Topology
from .det import cross


def corner_vertices(topology: Topology) -> np.ndarray:
    """(c, 3) int: for every corner its vertex, the next and the previous vertex of its face."""
    t = topology
    return np.stack([t.corner_vertex, t.corner_next_vertex, t.corner_prev_vertex], axis=1)


def angle_values(P: np.ndarray) -> np.ndarray:
    """(c,) float: the angles of corners ``P (c, 3, 3)`` (as :func:`angle_local`, values only)."""
    u = P[:, 1] - P[:, 0]
    w = P[:, 2] - P[:, 0]
    nrm = cross(u, w)
    return np.arctan2(np.sqrt(np.einsum("ij,ij->i", nrm, nrm)), np.einsum("ij,ij->i", u, w))


def angle_local(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Angles and gradients of corners given by their three points.

    P : (c, 3, 3) float, ``P[:, 0]`` the corner, ``P[:, 1]`` the next and
        ``P[:, 2]`` the previous vertex.
    Returns ``phi (c,)`` and ``G (c, 9)`` = ``d phi / d P.reshape(c, 9)``.
    """
    u = P[:, 1] - P[:, 0]
    w = P[:, 2] - P[:, 0]
    nrm = cross(u, w)
    s = np.sqrt(np.einsum("ij,ij->i", nrm, nrm))
    phi = np.arctan2(s, np.einsum("ij,ij->i", u, w))
    uu = np.maximum(np.einsum("ij,ij->i", u, u), 1e-300)  # zero-length edges: zero gradient
    ww = np.maximum(np.einsum("ij,ij->i", w, w), 1e-300)
    inv = np.where(s > 0, 1.0 / np.where(s > 0, s, 1.0), 0.0)
    gu = cross(u, nrm) * (inv / uu)[:, None]
    gw = cross(nrm, w) * (inv / ww)[:, None]
    return phi, np.concatenate([-(gu + gw), gu, gw], axis=1)


def corner_angle_terms(topology: Topology, V: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Angles and per-corner Jacobian triplets.

    Parameters
    ----------
    topology : Topology of the mesh (``c`` corners).
    V : (n, 3) float, vertex positions.

    Returns
    -------
    phi : (c,) float, interior angle at every corner (radians).
    cols : (c, 9) int, columns in the stacked vector ``x = V.ravel()``: the
        coordinates of the corner vertex, its next and its previous vertex.
    vals : (c, 9) float, ``d phi / d x`` at those columns.
    """
    vid = corner_vertices(topology)
    phi, vals = angle_local(V[vid])
    cols = (3 * vid[:, :, None] + np.arange(3)[None, None, :]).reshape(-1, 9)
    return phi, cols, vals


def sign_matrix(corners: np.ndarray, signs, n_corners: int) -> sp.csr_matrix:
    """(r, c) sparse ``S`` with ``r = S @ phi + const`` for the rows of :func:`combine`."""
    corners = np.asarray(corners)
    signs = np.broadcast_to(np.asarray(signs, dtype=float), corners.shape)
    mask = corners >= 0
    return sp.csr_matrix((signs[mask], (np.nonzero(mask)[0], corners[mask])),
                         shape=(corners.shape[0], n_corners))


def combine(phi: np.ndarray, cols: np.ndarray, vals: np.ndarray, corners: np.ndarray,
            signs: np.ndarray, const: np.ndarray, n_vertices: int) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residuals ``r_i = sum_j signs[i, j] * phi[corners[i, j]] + const[i]`` and their Jacobian.

    Parameters
    ----------
    phi, cols, vals : from :func:`corner_angle_terms`, ``(c,)``, ``(c, 9)``, ``(c, 9)``.
    corners : (r, k) int, corner indices of each residual, ``-1`` for unused slots.
    signs : (r, k) or (k,) float, coefficient of each corner angle.
    const : (r,) float, constant term of each residual.
    n_vertices : n, the Jacobian has ``3 n`` columns.

    Returns
    -------
    r : (r,) float residuals.
    J : (r, 3 n) sparse CSR Jacobian ``d r / d x`` with ``x = V.ravel()``.
    """
    corners = np.asarray(corners)
    nr = corners.shape[0]
    signs = np.broadcast_to(np.asarray(signs, dtype=float), corners.shape)
    mask = corners >= 0
    row = np.nonzero(mask)[0]
    c = corners[mask]
    s = signs[mask]
    r = np.bincount(row, weights=s * phi[c], minlength=nr) + const
    data = (s[:, None] * vals[c]).ravel()
    J = sp.csr_matrix((data, (np.repeat(row, 9), cols[c].ravel())), shape=(nr, 3 * n_vertices))
    return r, J


def face_corners(topology: Topology, faces: np.ndarray) -> np.ndarray:
    """(len(faces), kmax) int: corner indices of the given faces, ``-1`` padded."""
    sizes = topology.face_sizes[faces]
    k = int(sizes.max(initial=0))
    j = np.arange(k)[None, :]
    return np.where(j < sizes[:, None], topology.offsets[faces][:, None] + j, -1)
