"""Support beams: one quadrilateral per edge between two offset layers.

The beam on edge ``(a, b)`` between the layers at ``d0`` and ``d1`` is the quad
``[a@d0, b@d0, b@d1, a@d1]``; its long sides lie on the node axes of ``a`` and
``b``.  For a conical mesh the axes of neighbouring vertices are coplanar with
their edge (paper, Geometry Fact 2) and the quad is planar: a torsion-free
beam.  Otherwise the beam twists:

- ``twist_mm``: the distance between the quad's two diagonal lines (the
  planarity measure of the package, in model units, not divided by a length);
- ``twist_deg``: the signed dihedral angle about the edge between the planes
  (edge, side at ``a``) and (edge, side at ``b``): how far one end of the
  beam is rotated against the other.
"""
from __future__ import annotations

import numpy as np

from optimize.mesh.measures import quad_planarity


def beam_quads(edges: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(e, 4, 3) float: ``[a@d0, b@d0, b@d1, a@d1]`` for ``edges (e, 2)``, layers ``(n, 3)``."""
    a, b = edges[:, 0], edges[:, 1]
    return np.stack([lower[a], lower[b], upper[b], upper[a]], axis=1)


def beam_normals(Q: np.ndarray) -> np.ndarray:
    """(e, 3) float: unit normal of the beam plane, ``(Q2 - Q0) x (Q3 - Q1)`` normalized.

    For a twisted quad this is the plane parallel to both diagonals.  A
    degenerate quad (parallel diagonals) falls back to ``(Q1 - Q0) x (Q3 - Q0)``.
    """
    n = np.cross(Q[:, 2] - Q[:, 0], Q[:, 3] - Q[:, 1])
    alt = np.cross(Q[:, 1] - Q[:, 0], Q[:, 3] - Q[:, 0])
    ln = np.linalg.norm(n, axis=1, keepdims=True)
    scale = np.linalg.norm(Q[:, 2] - Q[:, 0], axis=1, keepdims=True) ** 2
    n = np.where(ln > 1e-12 * scale, n, alt)
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def beam_twist(Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Twist of beam quads ``Q (e, 4, 3)``.

    Returns
    -------
    twist_mm : (e,) float, distance between the diagonal lines ``Q0 Q2`` and ``Q1 Q3``
    twist_deg : (e,) float, signed dihedral angle about ``Q0 Q1`` between the
        half-planes through ``Q3`` and ``Q2`` (degrees)
    """
    l1 = np.linalg.norm(Q[:, 2] - Q[:, 0], axis=1)
    l2 = np.linalg.norm(Q[:, 3] - Q[:, 1], axis=1)
    mm = quad_planarity(Q) * 0.5 * (l1 + l2)
    gap = Q[:, 1] - Q[:, 0]
    e = gap / np.linalg.norm(gap, axis=1, keepdims=True)
    sa = Q[:, 3] - Q[:, 0]
    sb = Q[:, 2] - Q[:, 1]
    pa = sa - np.einsum("ij,ij->i", sa, e)[:, None] * e
    pb = sb - np.einsum("ij,ij->i", sb, e)[:, None] * e
    deg = np.degrees(np.arctan2(np.einsum("ij,ij->i", e, np.cross(pa, pb)),
                                np.einsum("ij,ij->i", pa, pb)))
    return mm, deg


def beam_planarity(Q: np.ndarray) -> np.ndarray:
    """(e,) float: planarity of the beam quads ``Q (e, 4, 3)`` (the package's definition)."""
    return quad_planarity(Q)
