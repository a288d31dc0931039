"""Conical angle balance (paper eq. 6): ``w1 + w3 - w2 - w4 = 0`` per interior valence-4 vertex.

``w1..w4`` are the corner angles at the vertex in cyclic order
(``topology.star_corners``).  By Geometry Fact 1 of the paper the four face
planes of a planar-faced star then touch a cone of revolution.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ...mesh import Mesh
from ...mesh.corners import corner_angle_gradients
from ...terms import anglebalance
from .combine import combine


def balance_rows(mesh: Mesh):
    """Row spec ``(corners (p, 4), signs (4,), const (p,))`` for :func:`optimize.solvers.paper.combine.combine`:
    the corner sets of :func:`optimize.terms.anglebalance.rows` (the default method's)."""
    corners, signs, offset = anglebalance.rows(mesh)
    return corners, signs, -offset


def angle_balance(mesh: Mesh, V: np.ndarray, terms=None) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual per ``topology.interior_valence4`` vertex and its Jacobian.

    Parameters
    ----------
    mesh : Mesh.  V : (n, 3) float.  terms : optional :func:`corner_angle_gradients` of ``V``.

    Returns
    -------
    r : (p,) float, ``w1 - w2 + w3 - w4`` (radians).
    J : (p, 3 n) sparse CSR.
    """
    phi, cols, vals = corner_angle_gradients(mesh.topology, V) if terms is None else terms
    return combine(phi, cols, vals, *balance_rows(mesh), mesh.n_vertices)
