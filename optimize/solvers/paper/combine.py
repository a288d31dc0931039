"""Signed sums of corner angles as residuals with a sparse Jacobian: the paper's angle constraints.

The angles and their gradients are :mod:`optimize.mesh.corners`'s.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...mesh.topology import Topology


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
    phi, cols, vals : from :func:`optimize.mesh.corners.corner_angle_gradients`, ``(c,)``, ``(c, 9)``, ``(c, 9)``.
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
