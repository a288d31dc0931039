"""Node axes of a polygon mesh: the one fit every stage uses (paper section 4).

At a vertex ``v`` with faces ``f_1 .. f_k`` and unit face normals ``n_i``,
an *offset vector* ``X_v (3,)`` moves ``v`` to ``v + d X_v`` so that every
face plane moves by exactly ``d``: ``n_i . X_v = 1`` for all ``i``.  Written
as ``X_v = a_v / cos(theta_v)`` with a unit *node axis* ``a_v``, this says
every face makes the angle ``theta_v`` with the axis: the face planes touch
one cone of revolution with axis ``a_v`` (a conical vertex), and the normals
``n_i`` lie on a circle of the unit sphere whose spherical centre is ``a_v``.

We solve ``N_v X_v = 1`` (``N_v (k, 3)`` the stacked normals) in the least
squares sense for every vertex at once (batched SVD):

- ``k >= 3`` normals spanning space: the exact cone when the vertex is
  conical, otherwise the least-squares point of the offset planes (the
  ``defect`` says how far from conical);
- fewer independent normals (``k = 1, 2``, a boundary vertex; or a cylinder-
  or flat-like vertex whose normals span a plane or a line): the minimum-norm
  solution, i.e. the bisector of two normals, or the normal itself.  Such a
  vertex keeps ``free_rank`` degrees of freedom that do not change any face
  distance (``free_basis``); :mod:`fabricate.offset.straighten` uses them to
  make the beams planar.  At a conical vertex (axis defect below
  ``NEAR_CONICAL``) singular values of ``N_v`` below ``AXIS_NEAR = 1e-3`` of the
  largest count as zero as well: at a nearly cylindrical vertex the exact cone
  axis is ill-conditioned (a conical defect of 2e-8 rad tilted the axes of a
  remeshed tube so far that beams twisted by 0.6 mm), while turning along such
  a direction changes face distances by at most ``1e-3`` of the turn (0.0001 mm
  on that tube, whose beams are then planar to 0.0002 mm); the face-distance
  error stays measured and reported.  Non-conical vertices keep the exact
  least-squares axis.

``cos(theta_v) = 1 / |X_v| > 0``: the axis points to the side of the normals.

Users: the optimizer's result axes (default and paper methods), the starting
values of the auxiliary conical formulation (:func:`fit_star_axes` on the
four normals of each cone vertex) and the offset stage
(:mod:`fabricate.offset.axes`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .core import Mesh

AXIS_RCOND = 1e-10
"""Singular values of ``N_v`` below ``AXIS_RCOND * sigma_max`` count as zero (free directions)."""

AXIS_NEAR = 1e-3
"""At a conical vertex (axis defect below ``NEAR_CONICAL``), singular values below
``AXIS_NEAR * sigma_max`` count as zero too (a nearly cylindrical vertex; see above)."""

NEAR_CONICAL = 1e-4
"""Radians: the axis defect below which a vertex counts as conical for ``AXIS_NEAR``."""


@dataclass(frozen=True)
class AxisFit:
    """Node axes of every vertex.

    offset : (n, 3) float, ``X_v = a_v / cos(theta_v)`` (a layer at ``d`` is ``V + d * offset``)
    axes : (n, 3) float, unit node axes ``a_v``
    cos_theta : (n,) float, ``1 / |X_v|`` (> 0)
    defect : (n,) float, radians: half the spread of the angles between ``a_v``
        and the normals of the faces at ``v`` (0 exactly when they touch one cone)
    free_basis : (n, 3, 2) float, orthonormal directions ``z`` with ``n_i . z = 0``
        for every face at ``v`` (zero columns beyond ``free_rank``)
    free_rank : (n,) int, number of such directions (0, 1 or 2)
    """

    offset: np.ndarray
    axes: np.ndarray
    cos_theta: np.ndarray
    defect: np.ndarray
    free_basis: np.ndarray
    free_rank: np.ndarray


def star_normals(mesh: Mesh, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normals of the faces around every vertex.

    Returns ``Ns (n, s, 3)`` (zero rows in padding) and ``valid (n, s)`` bool.
    """
    sf = mesh.topology.star_faces
    valid = sf >= 0
    Ns = np.where(valid[..., None], normals[np.maximum(sf, 0)], 0.0)
    return Ns, valid


def angle_spread(Ns: np.ndarray, valid: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """(n,) float: half the spread of ``angle(n_i, a_v)`` over the valid star faces (radians)."""
    A = np.broadcast_to(axes[:, None, :], Ns.shape)
    ang = np.arctan2(np.linalg.norm(np.cross(Ns, A), axis=2), np.einsum("nsj,nsj->ns", Ns, A))
    hi = np.where(valid, ang, -np.inf).max(axis=1)
    lo = np.where(valid, ang, np.inf).min(axis=1)
    return 0.5 * (hi - lo)


def fit_star_axes(Ns: np.ndarray, valid: np.ndarray, rcond: float = AXIS_RCOND,
                  near: float = AXIS_NEAR) -> AxisFit:
    """Least-squares node axes from stacked star normals (see the module text).

    Parameters
    ----------
    Ns : (p, s, 3) float, unit normals around each of ``p`` vertices (zero rows in padding)
    valid : (p, s) bool, which rows of ``Ns`` are faces
    rcond : relative singular-value cut-off for free directions
    near : the cut-off at conical vertices (``AXIS_NEAR``; ``near <= rcond`` gives the exact axes)
    """
    b = valid.astype(float)  # (p, s): right-hand side 1 per face, 0 in padding
    U, S, Vt = np.linalg.svd(Ns, full_matrices=False)  # (p,s,3) (p,3) (p,3,3)

    def solve(cut):
        keep = S > cut[:, None] * S[:, :1]
        coef = np.where(keep, np.einsum("nsi,ns->ni", U, b) / np.where(keep, S, 1.0), 0.0)
        X = np.einsum("ni,nij->nj", coef, Vt)
        cos_theta = 1.0 / np.linalg.norm(X, axis=1)
        return keep, X, cos_theta, X * cos_theta[:, None]

    keep, X, cos_theta, axes = solve(np.full(len(S), rcond))
    conical = angle_spread(Ns, valid, axes) < NEAR_CONICAL  # an ill-conditioned axis may turn
    if conical.any() and rcond < near:
        keep, X, cos_theta, axes = solve(np.where(conical, near, rcond))
    free = ~keep  # (p, 3), singular values sorted descending: free ones are last
    free_rank = free.sum(axis=1)
    basis = np.zeros((len(X), 3, 2))
    basis[:, :, 0] = np.where(free[:, 2:3], Vt[:, 2, :], 0.0)
    basis[:, :, 1] = np.where(free[:, 1:2], Vt[:, 1, :], 0.0)
    return AxisFit(offset=X, axes=axes, cos_theta=cos_theta, defect=angle_spread(Ns, valid, axes),
                   free_basis=basis, free_rank=free_rank)


def fit_axes(mesh: Mesh, normals: np.ndarray, rcond: float = AXIS_RCOND,
             near: float = AXIS_NEAR) -> AxisFit:
    """Node axes of every vertex of ``mesh`` from its unit oriented face normals ``normals (m, 3)``
    (:func:`fit_star_axes` over the vertex stars)."""
    return fit_star_axes(*star_normals(mesh, normals), rcond=rcond, near=near)
