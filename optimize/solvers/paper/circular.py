"""Circular quads (paper eq. 7): ``phi1 + phi3 - pi = 0`` and ``phi2 + phi4 - pi = 0`` per quad.

A planar quad has a circumcircle exactly when its opposite angles add up to
``pi``; the two rows together imply the angle sum ``2 pi`` and replace it.
Rows are ordered ``(2 i, 2 i + 1)`` for the ``i``-th quad face
(``np.nonzero(mesh.face_sizes == 4)``).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...mesh import Mesh
from ...mesh.corners import corner_angle_gradients
from ...terms import anglesum
from .combine import combine


def circular_rows(mesh: Mesh):
    """Row spec ``(corners (2 q, 2), signs, const (2 q,))`` for :func:`optimize.solvers.paper.combine.combine`."""
    corners, signs, offset = anglesum.rows(mesh)  # the default method's corner pairs
    return corners, 1.0, -offset


def circular_angles(mesh: Mesh, V: np.ndarray, terms=None) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residuals ``(phi1 + phi3 - pi, phi2 + phi4 - pi)`` per quad and their Jacobian.

    Parameters
    ----------
    mesh : Mesh.  V : (n, 3) float.  terms : optional :func:`corner_angle_gradients` of ``V``.

    Returns
    -------
    r : (2 q,) float (radians).
    J : (2 q, 3 n) sparse CSR.
    """
    phi, cols, vals = corner_angle_gradients(mesh.topology, V) if terms is None else terms
    return combine(phi, cols, vals, *circular_rows(mesh), mesh.n_vertices)
