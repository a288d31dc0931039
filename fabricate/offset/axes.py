"""Face planes and node axes (paper section 4).

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
  ``axis_defect`` says how far from conical);
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
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from optimize.errors import MeshError
from optimize.mesh.measures import face_normals
from optimize.mesh import Mesh

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


def check_orientable(mesh: Mesh) -> None:
    """Raise :class:`MeshError` unless the faces of ``mesh`` can be oriented consistently."""
    if not mesh.topology.orientable:
        raise MeshError(f"{mesh.name}: the surface is not orientable (e.g. a Moebius band), "
                        "expected an orientable mesh: offset layers need one consistent side")


def face_planes(mesh: Mesh, flip: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Oriented face planes ``n_f . x = h_f``.

    Normals follow the face order (counter-clockwise seen from the normal side;
    Newell's method, the least-squares normal of a non-planar face); ``flip``
    reverses them.  ``h_f`` is the mean of ``n_f . v`` over the face's vertices.

    Returns
    -------
    normals : (m, 3) float, unit
    heights : (m,) float
    """
    N = face_normals(mesh)
    if flip:
        N = -N
    F = mesh.F
    valid = F >= 0
    h = np.einsum("fkj,fj->fk", mesh.V[np.maximum(F, 0)], N)
    heights = np.where(valid, h, 0.0).sum(axis=1) / valid.sum(axis=1)
    return N, heights


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


def fit_axes(mesh: Mesh, normals: np.ndarray, rcond: float = AXIS_RCOND) -> AxisFit:
    """Least-squares node axes from the face normals (see the module text).

    Parameters
    ----------
    mesh : Mesh with ``n`` vertices and ``m`` faces
    normals : (m, 3) float, unit oriented face normals
    rcond : relative singular-value cut-off for free directions
    """
    Ns, valid = star_normals(mesh, normals)
    b = valid.astype(float)  # (n, s): right-hand side 1 per face, 0 in padding
    U, S, Vt = np.linalg.svd(Ns, full_matrices=False)  # (n,s,3) (n,3) (n,3,3)

    def solve(cut):
        keep = S > cut[:, None] * S[:, :1]
        coef = np.where(keep, np.einsum("nsi,ns->ni", U, b) / np.where(keep, S, 1.0), 0.0)
        X = np.einsum("ni,nij->nj", coef, Vt)
        cos_theta = 1.0 / np.linalg.norm(X, axis=1)
        return keep, X, cos_theta, X * cos_theta[:, None]

    keep, X, cos_theta, axes = solve(np.full(len(S), rcond))
    near = angle_spread(Ns, valid, axes) < NEAR_CONICAL  # conical: an ill-conditioned axis may turn
    if near.any() and rcond < AXIS_NEAR:
        keep, X, cos_theta, axes = solve(np.where(near, AXIS_NEAR, rcond))
    free = ~keep  # (n, 3), singular values sorted descending: free ones are last
    free_rank = free.sum(axis=1)
    basis = np.zeros((len(X), 3, 2))
    basis[:, :, 0] = np.where(free[:, 2:3], Vt[:, 2, :], 0.0)
    basis[:, :, 1] = np.where(free[:, 1:2], Vt[:, 1, :], 0.0)
    return AxisFit(offset=X, axes=axes, cos_theta=cos_theta, defect=angle_spread(Ns, valid, axes),
                   free_basis=basis, free_rank=free_rank)


def given_axes(mesh: Mesh, normals: np.ndarray, axes: np.ndarray,
               rcond: float = AXIS_RCOND) -> AxisFit:
    """Node axes supplied by the caller (e.g. the optimizer's ``result.axes``).

    Each row of ``axes (n, 3)`` is normalized and turned to the normals' side;
    rows that are zero or not finite are replaced by :func:`fit_axes`.  The
    offset length along a given axis is the least-squares one:
    ``1 / cos(theta_v) = sum(n_i . a) / sum((n_i . a)^2)``.  Given axes carry no
    free directions.
    """
    axes = np.asarray(axes, dtype=float)
    if axes.shape != (mesh.n_vertices, 3):
        raise MeshError(f"{mesh.name}: node axes have shape {axes.shape}, "
                        f"expected ({mesh.n_vertices}, 3)")
    fit = fit_axes(mesh, normals, rcond)
    length = np.linalg.norm(axes, axis=1)
    use = np.isfinite(axes).all(axis=1) & (length > 0)
    A = np.where(use[:, None], axes / np.where(use, length, 1.0)[:, None], fit.axes)
    Ns, valid = star_normals(mesh, normals)
    dots = np.einsum("nsj,nj->ns", Ns, A)  # zero in padding
    s1, s2 = dots.sum(axis=1), (dots ** 2).sum(axis=1)
    A = np.where((s1 < 0)[:, None], -A, A)
    s1 = np.abs(s1)
    if np.any(s1 <= 1e-12 * np.maximum(s2, 1e-300)):
        v = int(np.argmax(s1 <= 1e-12 * np.maximum(s2, 1e-300)))
        raise MeshError(f"{mesh.name}: the given node axis at vertex {v} {A[v].tolist()} is "
                        "perpendicular to its face normals, expected an axis with cos(theta) > 0")
    scale = s1 / s2
    X = A * scale[:, None]
    free = np.zeros((len(A), 3, 2))
    return AxisFit(offset=X, axes=A, cos_theta=1.0 / scale, defect=angle_spread(Ns, valid, A),
                   free_basis=np.where(use[:, None, None], free, fit.free_basis),
                   free_rank=np.where(use, 0, fit.free_rank))
