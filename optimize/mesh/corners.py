"""Corner angles and their exact gradients: the one kernel behind every angle in ``optimize``.

The measures (:func:`optimize.mesh.measures.corner_angles`), the angle
constraints of both methods (:mod:`optimize.terms.angles`: angle sum, conical
balance, circular pairs, each a signed sum of corner angles minus a constant;
the paper's methods evaluate the same rows on fixed patterns,
:mod:`optimize.solvers.paper.system`) and the strip analysis all take their angles from here; the compiled counterpart is
``optimize.kernels`` ``angles``.  For every corner ``c`` of the mesh
(``topology`` corner order) the angle is

    phi_c = angle(u, w),  u = V[next] - V[p],  w = V[prev] - V[p],  p = V[corner_vertex]

with ``phi = atan2(|u x w|, u . w)`` (accurate near 0 and pi) and its gradient with
respect to the three vertices involved (signed sums of angles become residual
rows and a sparse Jacobian in :func:`optimize.terms.angles.angle_rows`).

Gradients (``nrm = u x w``)::

    d phi / d u = (u x nrm) / (|u|^2 |nrm|)      d phi / d w = (nrm x w) / (|w|^2 |nrm|)
    d phi / d p = -(d phi / d u + d phi / d w)

At a degenerate corner (``u`` parallel to ``w``) the angle is not
differentiable; the gradient returned there is zero.
"""
from __future__ import annotations

import numpy as np

from .topology import Topology


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product over the last axis (size 3) of ``a, b (..., 3)``; cheaper than ``np.cross`` on small batches."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def corner_vertices(topology: Topology) -> np.ndarray:
    """(c, 3) int: for every corner its vertex, the next and the previous vertex of its face."""
    t = topology
    return np.stack([t.corner_vertex, t.corner_next_vertex, t.corner_prev_vertex], axis=1)


def angle_values(P: np.ndarray) -> np.ndarray:
    """(c,) float: the angles of corners ``P (..., 3, 3)`` (as :func:`angle_local`, values only;
    ``P[..., 0]`` the corner, ``P[..., 1]`` the next, ``P[..., 2]`` the previous vertex)."""
    u = P[..., 1, :] - P[..., 0, :]
    w = P[..., 2, :] - P[..., 0, :]
    nrm = cross(u, w)
    return np.arctan2(np.sqrt(np.einsum("...j,...j->...", nrm, nrm)), np.einsum("...j,...j->...", u, w))


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


def corner_angle_gradients(topology: Topology, V: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
