"""Offset layers at signed distances and how far each face is from ``d``.

A layer at distance ``d`` has the vertices ``V + d X`` with the offset
vectors ``X_v = a_v / cos(theta_v)`` (:mod:`fabricate.offset.axes`), the same
vertex order and faces as the input.  For a conical mesh every face plane
moves by exactly ``d``; otherwise the faces at a vertex disagree and the
errors below say by how much.
"""
from __future__ import annotations

import numpy as np

from optimize.mesh import Mesh


def offset_layers(V: np.ndarray, offset: np.ndarray, distances) -> tuple[np.ndarray, ...]:
    """One ``(n, 3)`` array ``V + d * offset`` per distance (``V, offset (n, 3)``)."""
    return tuple(V + float(d) * offset for d in distances)


def face_offset_heights(mesh: Mesh, normals: np.ndarray, layer: np.ndarray) -> np.ndarray:
    """(m, k) float: ``n_f . (w_j - v_j)``, how far each corner moved along its face normal.

    ``layer (n, 3)`` are the offset positions ``w``; padding slots are NaN.
    A face that moved exactly ``d`` has ``d`` in every slot.
    """
    F = mesh.F
    valid = F >= 0
    D = layer[np.maximum(F, 0)] - mesh.V[np.maximum(F, 0)]  # (m, k, 3)
    h = np.einsum("mkj,mj->mk", D, normals)
    return np.where(valid, h, np.nan)


def face_distance_errors(mesh: Mesh, normals: np.ndarray, layers, distances
                         ) -> tuple[np.ndarray, np.ndarray]:
    """Distance error and spread of every offset face, in model units (mm).

    For each layer at distance ``d`` and face ``f``:
    ``error = max_j |n_f . (w_j - v_j) - d|`` (how far the worst corner of the
    offset face is from the original face plane moved by ``d``) and
    ``spread = max_j - min_j`` of ``n_f . (w_j - v_j)`` (how far the offset face
    is from parallel).  Non-planarity of the input face itself is not counted
    here (it is reported as planarity).

    Returns
    -------
    error : (m, L) float
    spread : (m, L) float
    """
    err, spread = [], []
    for layer, d in zip(layers, distances):  # one pass per layer, not per face
        h = face_offset_heights(mesh, normals, layer)
        err.append(np.nanmax(np.abs(h - float(d)), axis=1))
        spread.append(np.nanmax(h, axis=1) - np.nanmin(h, axis=1))
    return np.stack(err, axis=1), np.stack(spread, axis=1)
