"""``to_cadquery(parts)``: a ``cadquery.Assembly`` of every part, named by id and coloured by kind.

cadquery is an optional extra (``pip install ".[cadquery]"``): cadquery 2.8 and
build123d 0.13 each bring their own OpenCASCADE build (``OCP``) and break each
other, so the extra pins a set that shares one (cadquery 2.7, build123d 0.10,
cadquery-ocp 7.8.1, ocp_gordon below 0.2).  The default install does not
need cadquery; this module imports it only when called.

Every part is a planar-faced polyhedron: each face a closed polygon wire, the
faces sewn into a shell, the shell made a solid (exact: no tessellation).
"""
from __future__ import annotations

from ..cad.parts import COLOURS


def _solid(cq, V, faces):
    """A cadquery Solid of the polyhedron ``V (nv, 3)`` with outward ``faces``."""
    cq_faces = [cq.Face.makeFromWires(cq.Wire.makePolygon([cq.Vector(*V[i]) for i in f], close=True))
                for f in faces]
    return cq.Solid.makeSolid(cq.Shell.makeShell(cq_faces))


def to_cadquery(parts, name: str = "roof"):
    """``cadquery.Assembly`` with one child per part (name = part id, colour by kind), in mm.

    Raises ImportError with the install line when cadquery is not installed.
    """
    try:
        import cadquery as cq
    except ImportError as exc:
        raise ImportError(f"to_cadquery needs the cadquery extra: pip install \".[cadquery]\" ({exc})") from None
    assy = cq.Assembly(name=name)
    for g in parts.groups:
        colour = cq.Color(*COLOURS[g.kind], 0.6 if g.kind == "panel" else 1.0)
        for i, pid in enumerate(g.ids):
            assy.add(_solid(cq, g.vertices[i].tolist(), g.faces), name=pid, color=colour)
    return assy
