"""Face planes and node axes (paper section 4).

The node-axis fit itself (the least-squares offset vector ``X_v`` with
``n_i . X_v = 1``, free directions, the conditioning at nearly cylindrical
conical vertices) is :mod:`optimize.mesh.axes`, shared with the optimizer;
this module adds the oriented face planes, the offset stage's cut-off
(``AXIS_NEAR`` here is read at call time) and axes given by the caller.
"""
from __future__ import annotations

import numpy as np

from optimize.errors import MeshError
from optimize.mesh import Mesh
from optimize.mesh.axes import (
    AXIS_NEAR,
    AXIS_RCOND,
    NEAR_CONICAL,
    AxisFit,
    angle_spread,
    star_normals,
)
from optimize.mesh.axes import fit_axes as _fit_axes
from optimize.mesh.measures import face_normals

__all__ = ["AXIS_NEAR", "AXIS_RCOND", "NEAR_CONICAL", "AxisFit", "angle_spread", "check_orientable",
           "face_planes", "fit_axes", "given_axes", "star_normals"]


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


def fit_axes(mesh: Mesh, normals: np.ndarray, rcond: float = AXIS_RCOND) -> AxisFit:
    """Least-squares node axes from the face normals (:func:`optimize.mesh.axes.fit_axes`).

    Parameters
    ----------
    mesh : Mesh with ``n`` vertices and ``m`` faces
    normals : (m, 3) float, unit oriented face normals
    rcond : relative singular-value cut-off for free directions
    """
    return _fit_axes(mesh, normals, rcond, near=AXIS_NEAR)


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
