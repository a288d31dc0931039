"""Hubs on the node axes: a steel tube with a top and a bottom cap plate, or a solid polygonal hub.

The hub of vertex ``v`` stands on the node axis between the first and the
last layer, its height from the layers: the ends are recessed by
``r tan(theta_max)`` (the largest angle between the axis and a face normal
around ``v``) so that no cap reaches through a face plane into the glass
(:func:`fabricate.cad.nodes.node_solids`, which builds the solid hub).  The
beams stop at the hub radius with square ends (or further out, so that
neighbours cannot touch).

``tube``: three parts a shop makes from a tube and a plate:

- the tube (member ``tube``): a ``K``-gon of circumradius ``r`` outside and
  ``r - wall / cos(pi / K)`` inside (a wall ``wall`` thick, its ``thickness``), between the caps.
  As planar faces it has ``4 K`` convex quads (outside, inside and each end
  annulus split into ``K`` trapezoids), which STEP, STL, 3MF and the checks
  write exactly; :func:`tube_breps` builds its B-rep with build123d (one
  annular face per end, a face with a hole: what polyhedra with convex faces
  cannot express) for the OpenCASCADE writer and :meth:`Parts.to_build123d`.
- the top and bottom cap plates (``top cap``, ``bottom cap``): ``K``-gon prisms
  of radius ``r``, ``cap`` thick (their ``thickness``), cut from plate: their flat
  data (outline face: the lower face, whose normal points down the axis) go to ``flat.json`` and the cut
  files of that plate thickness with the beams' plates
  (:func:`fabricate.cad.parts.cut_from_sheet`).
"""
from __future__ import annotations

import numpy as np

from optimize.errors import ConfigError

from .panels import prism_faces

MEMBERS = ("tube", "top cap", "bottom cap")


def tube_faces(k: int) -> tuple[tuple[int, ...], ...]:
    """Faces of a ``k``-gon tube: vertices outer lower ``0..k-1``, outer upper ``k..2k-1``, inner lower
    ``2k..3k-1``, inner upper ``3k..4k-1`` (outward; every face a convex quad)."""
    ol, ou, il, iu = (lambda j, o=o: o * k + j % k for o in range(4))
    out = [(ol(j), ol(j + 1), ou(j + 1), ou(j)) for j in range(k)]          # outside
    out += [(il(j), iu(j), iu(j + 1), il(j + 1)) for j in range(k)]         # inside (facing the axis)
    out += [(ou(j), ou(j + 1), iu(j + 1), iu(j)) for j in range(k)]         # upper annulus
    out += [(ol(j), il(j), il(j + 1), ol(j + 1)) for j in range(k)]         # lower annulus
    return tuple(out)


def tube_step_faces(k: int) -> tuple[tuple, tuple[int, ...]]:
    """The ``k``-gon tube of :func:`tube_faces` with annular ends: ``(faces, normal_of)``, ``2 k`` quads
    (outside, inside) then the upper and the lower end, each ``(outer loop, hole loop)`` (outer
    counter-clockwise about the outward normal, the hole clockwise); ``normal_of``: the face of
    :func:`tube_faces` whose normal each has."""
    ring = [tuple(o * k + j for j in range(k)) for o in range(4)]                 # ol, ou, il, iu
    quads = tube_faces(k)[:2 * k]
    upper = (ring[1], ring[3][::-1])                                               # normal +axis
    lower = (ring[0][::-1], ring[2])                                               # normal -axis
    return quads + (upper, lower), tuple(range(2 * k)) + (2 * k, 3 * k)


def tube_hubs(node: dict, wall: float, cap: float, node_ids, element) -> list[dict]:
    """Split solid hubs into tube, top cap and bottom cap: ``[{"member", "vertices", "normals", "faces", "length"}]``.

    node : :func:`fabricate.cad.nodes.node_solids` (``vertices (n, 2K, 3)`` lower ring then upper
    ring, ``normals (n, K + 2, 3)`` lower, upper, sides); wall, cap : mm.
    """
    V, N = node["vertices"], node["normals"]
    k = V.shape[1] // 2
    lo, hi = V[:, :k], V[:, k:]
    a = N[:, 1]                                             # along the axis, lower -> upper
    height = node["length"]
    short = height <= 2 * cap + 1e-6 * np.maximum(height, 1.0)
    if short.any():
        i = int(np.argmax(short))
        raise ConfigError(f"node {node_ids[i]} (vertex {int(element[i])}): hub height {height[i]:.1f} mm leaves no "
                          f"tube between two {cap:g} mm caps; reduce parts.node.cap_mm or parts.node.radius_mm, "
                          "or use parts.node.hub: solid")
    lo_c, hi_c = lo + cap * a[:, None, :], hi - cap * a[:, None, :]
    r = np.linalg.norm(lo[:, 0] - lo.mean(axis=1), axis=1)
    inner = 1.0 - wall / np.cos(np.pi / k) / r                        # scale of the inner polygon
    axis_lo = lo.mean(axis=1)[:, None, :] + cap * a[:, None, :]
    axis_hi = hi.mean(axis=1)[:, None, :] - cap * a[:, None, :]
    il = axis_lo + inner[:, None, None] * (lo_c - axis_lo)
    iu = axis_hi + inner[:, None, None] * (hi_c - axis_hi)
    tube_V = np.concatenate([lo_c, hi_c, il, iu], axis=1)
    side = N[:, 2:]
    tube_N = np.concatenate([side, -side, np.repeat(a[:, None, :], k, axis=1),
                             np.repeat(-a[:, None, :], k, axis=1)], axis=1)
    faces = prism_faces(k)
    return [
        {"member": "tube", "vertices": tube_V, "normals": tube_N, "faces": tube_faces(k), "length": height - 2 * cap,
         "back": k,  # flat data between an outside face and the inside face behind it (not cut from sheet)
         "thickness": np.full(len(V), float(wall))},  # the wall: what a shop reads as a tube's thickness
        {"member": "top cap", "vertices": np.concatenate([hi_c, hi], axis=1), "normals": N, "faces": faces,
         "length": np.full(len(V), cap), "thickness": np.full(len(V), cap)},
        {"member": "bottom cap", "vertices": np.concatenate([lo, lo_c], axis=1), "normals": N, "faces": faces,
         "length": np.full(len(V), cap), "thickness": np.full(len(V), cap)},
    ]


def tube_breps(group) -> list:
    """``TopoDS_Solid`` of every tube of a ``tube`` group, built with build123d: the outside polygon
    with the inside one as a hole, extruded along the axis (one annular face per end)."""
    from build123d import Face, Vector, Wire, extrude

    k = group.vertices.shape[1] // 4
    out = []
    for V in group.vertices:  # one B-rep per tube
        outer = Wire.make_polygon([Vector(*p) for p in V[:k]], close=True)
        inner = Wire.make_polygon([Vector(*p) for p in V[2 * k:3 * k]], close=True)
        face = Face(outer, [inner])
        d = V[k] - V[0]
        out.append(extrude(face, amount=float(np.linalg.norm(d)), dir=Vector(*(d / np.linalg.norm(d)))).wrapped)
    return out
