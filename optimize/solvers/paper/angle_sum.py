"""Planarity by the angle sum (paper section 2.2): ``c_pq = phi_1 + ... + phi_k - (k - 2) pi``.

A skew polygon has an angle sum below ``(k - 2) pi``; the sum reaches it for a
planar convex polygon, so ``c_pq = 0`` asks for planar *and* convex faces.
Triangles satisfy it identically and get no row.

Note the constraint is degenerate: ``c_pq <= 0`` near a planar convex face and
every angle is an even function of an out-of-plane displacement, so the
gradient of ``c_pq`` vanishes at a planar face.  Solvers therefore converge
linearly on it (the defect halves per Gauss-Newton step); see ``det.py`` for
the non-degenerate determinant form used on strips.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...mesh import Mesh
from ...mesh.corners import corner_angle_gradients
from .combine import combine, face_corners


def angle_sum_faces(mesh: Mesh) -> np.ndarray:
    """(r,) int: the faces that get an angle-sum row (every face with 4 or more vertices)."""
    return np.nonzero(mesh.face_sizes >= 4)[0]


def angle_sum_rows(mesh: Mesh, faces: np.ndarray | None = None):
    """Row spec ``(corners (r, k), signs, const (r,))`` for :func:`optimize.solvers.paper.combine.combine`."""
    t = mesh.topology
    faces = angle_sum_faces(mesh) if faces is None else np.asarray(faces, dtype=np.int64)
    return face_corners(t, faces), 1.0, -(t.face_sizes[faces] - 2) * np.pi


def angle_sum(mesh: Mesh, V: np.ndarray, faces: np.ndarray | None = None,
              terms=None) -> tuple[np.ndarray, sp.csr_matrix]:
    """Angle-sum residuals and Jacobian.

    Parameters
    ----------
    mesh : Mesh (topology used).
    V : (n, 3) float, positions.
    faces : (r,) int or None, faces to constrain (default :func:`angle_sum_faces`).
    terms : optional precomputed :func:`corner_angle_gradients` ``(phi, cols, vals)`` for ``V``.

    Returns
    -------
    r : (r,) float, ``sum of corner angles - (k - 2) pi`` (radians, <= 0 up to rounding).
    J : (r, 3 n) sparse CSR, ``d r / d x`` with ``x = V.ravel()``.
    """
    phi, cols, vals = corner_angle_gradients(mesh.topology, V) if terms is None else terms
    return combine(phi, cols, vals, *angle_sum_rows(mesh, faces), mesh.n_vertices)
