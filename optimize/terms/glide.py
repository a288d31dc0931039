"""Boundary gliding: boundary vertices stay on the reference's boundary curve.

The curve is the polyline of boundary edges of the reference mesh.  With
footpoint ``y`` on the curve and unit tangent ``t`` there, the two residuals
of a vertex are ``(v - y) . e1`` and ``(v - y) . e2`` with ``e1, e2`` an
orthonormal basis of the plane normal to ``t``: the vertex may slide along
the curve (the tangent-line approximation; footpoints are recomputed every
iteration).  Closest points: :class:`optimize.proximity.BoundaryCurve`.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..proximity.curve import BoundaryCurve
from .variables import Layout


def normal_frame(T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors ``(k, 3)`` each, orthonormal and normal to unit tangents ``T (k, 3)``."""
    helper = np.where((np.abs(T[:, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    e1 = np.cross(T, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return e1, np.cross(T, e1)


def terms(x: np.ndarray, layout: Layout, vertices: np.ndarray, curve: BoundaryCurve,
          footpoints: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual ``(2b,)`` and Jacobian ``(2b, layout.size)`` for boundary ``vertices (b,)``.

    ``footpoints = (Y, T)`` may be passed to keep them fixed (they are then
    the linearization point: the residual is linear in ``x``).
    """
    V = layout.view(x, "vertices")[vertices]
    Y, T = curve.closest(V) if footpoints is None else footpoints
    e1, e2 = normal_frame(T)
    g = V - Y
    r = np.stack([np.einsum("ij,ij->i", g, e1), np.einsum("ij,ij->i", g, e2)], axis=1).ravel()
    b = len(vertices)
    cols = np.repeat(layout.index("vertices")[vertices], 2, axis=0)  # (2b, 3)
    vals = np.stack([e1, e2], axis=1).reshape(2 * b, 3)
    J = sp.csr_matrix((vals.ravel(), (np.repeat(np.arange(2 * b), 3), cols.ravel())),
                      shape=(2 * b, layout.size))
    return r, J
