"""OpenCASCADE solids from part polygons (shared vertices and edges, one plane per face).

A planar-faced polyhedron is assembled topologically with ``BRep_Builder``:
one ``TopoDS_Vertex`` per corner, one straight edge per polyhedron edge
(shared by its two faces, used once forward and once reversed), one
``Geom_Plane`` per face (the plane the face was built in: outward normal
from the part data, through the face's first corner).  No sewing and no
boolean is needed, and OpenCASCADE computes the p-curves of planar faces on
demand.  Every face's corners are within ``residual_mm`` (about 1e-11 mm) of
its plane, far below the vertex tolerance.
"""
from __future__ import annotations

import numpy as np

TOLERANCE_MM = 1e-7


def edge_table(faces: tuple[tuple[int, ...], ...]) -> tuple[np.ndarray, list[list[tuple[int, bool]]]]:
    """Unique edges ``(ne, 2)`` (lower index first) and, per face, ``(edge, forward)`` in loop order."""
    index: dict[tuple[int, int], int] = {}
    per_face = []
    for f in faces:
        row = []
        for j in range(len(f)):
            a, b = f[j], f[(j + 1) % len(f)]
            key = (min(a, b), max(a, b))
            if key not in index:
                index[key] = len(index)
            row.append((index[key], a < b))
        per_face.append(row)
    return np.array(list(index), dtype=np.int64).reshape(-1, 2), per_face


def group_solids(group) -> list:
    """``TopoDS_Solid`` of every part of a :class:`fabricate.cad.PartGroup`, in group order.

    A hub tube (``member == "tube"``) is built by build123d (:func:`fabricate.cad.hubs.tube_breps`:
    its ends are annuli, faces with a hole); every other part, convex faces, by ``BRep_Builder``.
    """
    if group.kind == "node" and group.member == "tube":
        from fabricate.cad.hubs import tube_breps

        return tube_breps(group)
    from OCP.BRep import BRep_Builder
    from OCP.Geom import Geom_Line, Geom_Plane
    from OCP.gp import gp_Dir, gp_Pnt
    from OCP.TopAbs import TopAbs_FORWARD, TopAbs_REVERSED
    from OCP.TopoDS import TopoDS_Edge, TopoDS_Face, TopoDS_Shell, TopoDS_Solid, TopoDS_Vertex, TopoDS_Wire

    B = BRep_Builder()
    E, per_face = edge_table(group.faces)
    first = [f[0] for f in group.faces]
    out = []
    for V, N in zip(group.vertices.tolist(), group.normals.tolist()):  # one OCC call chain per part
        pts = [gp_Pnt(*p) for p in V]
        verts = []
        for p in pts:
            v = TopoDS_Vertex()
            B.MakeVertex(v, p, TOLERANCE_MM)
            verts.append(v)
        edges = []
        for a, b in E.tolist():
            d = np.subtract(V[b], V[a])
            length = float(np.sqrt(d @ d))
            e = TopoDS_Edge()
            B.MakeEdge(e, Geom_Line(pts[a], gp_Dir(*(d / length))), TOLERANCE_MM)
            B.Add(e, verts[a].Oriented(TopAbs_FORWARD))
            B.Add(e, verts[b].Oriented(TopAbs_REVERSED))
            B.Range(e, 0.0, length)
            edges.append(e)
        shell = TopoDS_Shell()
        B.MakeShell(shell)
        for fi, row in enumerate(per_face):
            w = TopoDS_Wire()
            B.MakeWire(w)
            for ei, forward in row:
                B.Add(w, edges[ei] if forward else edges[ei].Reversed())
            w.Closed(True)
            face = TopoDS_Face()
            B.MakeFace(face, Geom_Plane(pts[first[fi]], gp_Dir(*N[fi])), TOLERANCE_MM)
            B.Add(face, w)
            B.Add(shell, face)
        shell.Closed(True)
        solid = TopoDS_Solid()
        B.MakeSolid(solid)
        B.Add(solid, shell)
        out.append(solid)
    return out


def solid_facts(shape) -> dict:
    """``{"valid", "volume_mm3", "solids", "faces"}`` of an OCC shape (BRepCheck_Analyzer, GProp)."""
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps
    from OCP.TopAbs import TopAbs_FACE, TopAbs_SOLID
    from OCP.TopExp import TopExp_Explorer

    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props)
    counts = {}
    for name, kind in (("solids", TopAbs_SOLID), ("faces", TopAbs_FACE)):
        ex, n = TopExp_Explorer(shape, kind), 0
        while ex.More():
            n += 1
            ex.Next()
        counts[name] = n
    return {"valid": bool(BRepCheck_Analyzer(shape).IsValid()), "volume_mm3": float(props.Mass()), **counts}
