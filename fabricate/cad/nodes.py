"""Nodes: a polygonal cylinder on every node axis (optional).

The node of vertex ``v`` is a regular ``node_sides``-gon prism of circumradius
``node_radius`` around the axis line, between the first and the last layer,
with both caps normal to the axis and recessed by ``r tan(theta_max)`` (the
largest angle between the axis and a face normal around ``v``), so that no
cap reaches through a face plane into the glass.  The beams stop at least
``node_radius`` from the axis, so they never enter a node.
"""
from __future__ import annotations

import numpy as np

from .beams import _node_frames
from .geometry import dot, unit
from .panels import prism_faces


def node_solids(structure, P0: np.ndarray, P1: np.ndarray, radius: float, sides: int) -> dict:
    """Vertices ``(n, 2 K, 3)``, outward normals ``(n, K + 2, 3)``, ``faces``, ``theta_max (n,)``.

    Same vertex and face layout as a panel (:func:`fabricate.cad.panels.prism_faces`):
    lower ring, upper ring (along the axis), caps first.  P0, P1 : (n, 3) vertex
    positions at the first and last layer.
    """
    mesh = structure.mesh
    topo = mesh.topology
    a = unit(np.asarray(structure.axes, dtype=float))
    N = unit(np.asarray(structure.normals, dtype=float))
    star = topo.star_faces                                  # (n, s), -1 padded
    cos_f = np.where(star >= 0, dot(N[np.maximum(star, 0)], a[:, None, :]), 1.0)
    theta = np.arccos(np.clip(cos_f.min(axis=1), -1.0, 1.0))
    recess = radius * np.tan(np.minimum(theta, np.radians(89.0)))
    z1 = dot(P1 - P0, a)                                    # signed axial length to the last layer
    direction = np.sign(z1)
    za = direction * recess
    zb = z1 - direction * recess
    z_lo, z_hi = np.minimum(za, zb), np.maximum(za, zb)
    fx, fy = _node_frames(a)
    phi = 2 * np.pi * np.arange(sides) / sides
    ring = radius * (np.cos(phi)[None, :, None] * fx[:, None, :] + np.sin(phi)[None, :, None] * fy[:, None, :])
    lo = P0[:, None, :] + z_lo[:, None, None] * a[:, None, :] + ring
    hi = P0[:, None, :] + z_hi[:, None, None] * a[:, None, :] + ring
    mid = phi + np.pi / sides
    side_n = np.cos(mid)[None, :, None] * fx[:, None, :] + np.sin(mid)[None, :, None] * fy[:, None, :]
    normals = np.concatenate([-a[:, None, :], a[:, None, :], side_n], axis=1)
    return {"vertices": np.concatenate([lo, hi], axis=1), "normals": normals,
            "faces": prism_faces(sides), "theta_max": theta, "length": z_hi - z_lo}
