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

from .geometry import unit
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
    """The faces STEP writes for a ``k``-gon tube of :func:`tube_faces`: ``(faces, normal_of)``, its ``4 k``
    quads as they are (a faceted hub's ends follow the glass planes: no plane annulus), ``normal_of``
    the face of :func:`tube_faces` whose normal each has."""
    return tube_faces(k), tuple(range(4 * k))


def faceted_tube_hubs(node: dict, wall: float, cap: float, node_ids, element) -> list[dict]:
    """A faceted hub as a shop builds it: the tube (:func:`fabricate.cad.nodes.faceted_nodes` with a
    wall, its flats and its ends in the glass planes) and two cap plates inside it, each the inner
    polygon ``cap`` thick, normal to the axis: the top one below the glass planes, the bottom one above
    the planes of the last layer (they close the tube; the beams' ends are closed by the flats).
    ``[{"member", "vertices", "normals", "faces", "length", "thickness", "select"}]``: ``select`` the
    group's nodes each batch holds (the caps come in batches by their corner count)."""
    from .nodes import face_normals

    V = node["vertices"]
    m = node["m"]
    bot, top, ibot, itop = V[:, :m], V[:, m:2 * m], V[:, 2 * m:3 * m], V[:, 3 * m:]
    a = unit(top.mean(axis=1) - bot.mean(axis=1))
    o = itop.mean(axis=1)
    zt = np.einsum("pki,pi->pk", itop - o[:, None], a)
    zb = np.einsum("pki,pi->pk", ibot - o[:, None], a)
    hi = np.minimum(zt.min(axis=1), np.einsum("pi,pi->p", node["apex"][:, 0] - o, a))
    lo = np.maximum(zb.max(axis=1), np.einsum("pi,pi->p", node["apex"][:, 1] - o, a))
    free = hi - lo
    short = free <= 2 * cap + 1e-6
    if short.any():
        i = int(np.argmax(short))
        raise ConfigError(f"node {node_ids[i]} (vertex {int(element[i])}): the hub's inside is {free[i]:.1f} mm "
                          f"high between the glass planes and the last layer, no room for two {cap:g} mm caps; "
                          "reduce parts.node.cap_mm or use parts.node.hub: solid")
    plan = itop - zt[..., None] * a[:, None, :]                       # the inner polygon at height 0
    corner = node["ridge"] < 0                                        # a cap's corners (not the ridge points)
    count = corner.sum(axis=1)
    caps = []
    for member, z0, z1 in (("top cap", hi - cap, hi), ("bottom cap", lo, lo + cap)):
        for c in np.unique(count):                                    # one batch per corner count
            sel = np.flatnonzero(count == c)
            pl = plan[sel][corner[sel]].reshape(len(sel), int(c), 3)
            P = np.concatenate([pl + (z0[sel] - 0)[:, None, None] * a[sel, None, :],
                                pl + z1[sel][:, None, None] * a[sel, None, :]], axis=1)
            faces = prism_faces(int(c))
            caps.append({"member": member, "vertices": P, "normals": face_normals(P, faces), "faces": faces,
                         "length": np.full(len(sel), cap), "thickness": np.full(len(sel), cap), "select": sel})
    tube = {"member": "tube", "vertices": V, "normals": node["normals"], "faces": tube_faces(m),
            "length": node["height"], "back": m, "thickness": np.full(len(V), float(wall)),
            "select": np.arange(len(V))}
    return [tube] + caps


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
    """``TopoDS_Solid`` of every tube of a ``tube`` group, built with build123d from its planar faces
    (the flats outside and inside, the ends in the glass planes)."""
    from build123d import Face, Shell, Solid, Vector, Wire

    out = []
    for V in group.vertices:  # one B-rep per tube
        faces = [Face(Wire.make_polygon([Vector(*V[j]) for j in f], close=True)) for f in group.faces]
        out.append(Solid(Shell(faces)).wrapped)
    return out
