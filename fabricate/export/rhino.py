"""Rhino ``.3dm`` (rhino3dm): every part, the design mesh, the offset layers and the node axes.

Layers: ``glass``, ``steel`` (beams), ``nodes``, ``design mesh``, ``offset layers``,
``node axes``.  Every part is one closed mesh object named by its id (the
id of the STEP file and the bill of materials), its faces the part's planar
faces (quads kept, larger polygons as fans of triangles), its vertices
stored in double precision so they equal the STEP's; the bill-of-materials
row is attached as user strings (``kind``, ``element``, ``volume_mm3``,
``weight_kg``, ...).  Units: millimetres.  In Rhino, ``_MeshToNURB`` (or
``_ToPolysurface`` in Rhino 8) turns a part into a polysurface.

rhino3dm is imported here only.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from optimize.atomic import atomic_path
from optimize.errors import ExportError

from .meshes import require_finite

LAYERS = (("glass", (140, 199, 230)), ("steel", (115, 120, 128)), ("nodes", (204, 115, 38)),
          ("design mesh", (60, 60, 60)), ("offset layers", (150, 150, 150)), ("node axes", (200, 40, 40)))
KIND_LAYER = {"panel": "glass", "beam": "steel", "node": "nodes"}


def _mesh(rh, V: np.ndarray, faces) -> object:
    """A rhino3dm Mesh of polygons ``faces`` over ``V (n, 3)`` (double precision vertices); ``faces``
    as rows (``-1`` padding), or a :func:`_template` mesh of them made once for the parts of a group
    (copied and its vertices set: its faces are not added again)."""
    m = faces.Duplicate() if isinstance(faces, rh.Mesh) else _template(rh, len(V), faces)
    point, set_point = rh.Point3d, m.Vertices.SetPoint3dAt
    for j, (x, y, z) in enumerate(V.tolist()):  # Vertices.Add(x, y, z) would round to float32
        set_point(j, point(x, y, z))
    m.Normals.ComputeNormals()
    m.Compact()
    return m


def _template(rh, n: int, faces) -> object:
    """A rhino3dm Mesh of ``n`` double-precision vertices (not yet placed) and the polygons ``faces``
    (rows, ``-1`` padding)."""
    m = rh.Mesh()
    m.Vertices.UseDoublePrecisionVertices = True
    m.Vertices.SetCount(n)
    add = m.Faces.AddFace
    for face in _mesh_faces(faces):
        add(*face)
    return m


def _mesh_faces(faces) -> list[tuple[int, ...]]:
    """Polygons as rhino3dm faces: triangles and quads as they are, larger ones as fans (the faces are
    planar and convex)."""
    out = []
    for face in faces:
        face = [int(i) for i in face if i >= 0]
        if len(face) in (3, 4):
            out.append(tuple(face))
        else:
            out.extend((face[0], face[j], face[j + 1]) for j in range(1, len(face) - 1))
    return out


def _attributes(rh, layer: int, name: str, strings: dict) -> object:
    a = rh.ObjectAttributes()
    a.LayerIndex = layer
    a.Name = name
    for key, value in strings.items():
        a.SetUserString(key, str(value))
    return a


def write_3dm(parts, path, *, structure=None, mesh=None) -> dict:
    """Write ``parts`` (and the design ``mesh``, default ``parts.mesh``; when given, the ``structure``'s layers and node axes)
    as a Rhino 7 ``.3dm`` file in millimetres (atomic).  Returns facts: ``file, bytes, objects`` per layer."""
    import rhino3dm as rh

    t0 = time.perf_counter()
    require_finite(parts)
    path = Path(path)
    mesh = mesh if mesh is not None else getattr(parts, "mesh", None)
    model = rh.File3dm()
    model.Settings.ModelUnitSystem = rh.UnitSystem.Millimeters
    index = {}
    for name, rgb in LAYERS:
        layer = rh.Layer()
        layer.Name = name
        layer.Color = (*rgb, 255)
        index[name] = model.Layers.Add(layer)
    counts = {name: 0 for name, _ in LAYERS}
    for g in parts.groups:
        layer = KIND_LAYER[g.kind]
        density = parts.spec.group_density(g)
        faces = _template(rh, g.vertices.shape[1], g.faces)   # the same polygons for every part of the group
        for i, pid in enumerate(g.ids):
            row = {"id": pid, "kind": g.kind, "element": int(g.element[i]),
                   "volume_mm3": repr(float(g.volume_mm3[i])),
                   "weight_kg": f"{g.volume_mm3[i] * density * 1e-9:.3f}",
                   "area_m2": f"{g.area_mm2[i] * 1e-6:.6f}", "length_mm": f"{g.length_mm[i]:.3f}",
                   "thickness_mm": f"{g.thickness_mm[i]:.3f}", "planarity_mm": f"{g.planarity_mm[i]:.3g}",
                   "neighbours": " ".join(g.neighbours[i])}
            model.Objects.AddMesh(_mesh(rh, g.vertices[i], faces), _attributes(rh, index[layer], pid, row))
            counts[layer] += 1
    if mesh is not None:
        model.Objects.AddMesh(_mesh(rh, mesh.V, mesh.F), _attributes(rh, index["design mesh"], "design", {}))
        counts["design mesh"] += 1
    if structure is not None:
        for i, d in enumerate(structure.distances):
            layer_mesh = structure.layer_mesh(i)
            model.Objects.AddMesh(_mesh(rh, layer_mesh.V, layer_mesh.F),
                                  _attributes(rh, index["offset layers"], f"layer_{i}", {"distance_mm": f"{d:g}"}))
            counts["offset layers"] += 1
        first, last = structure.layer_mesh(0).V, structure.layer_mesh(len(structure.distances) - 1).V
        for v, (a, b) in enumerate(zip(first.tolist(), last.tolist())):
            line = rh.LineCurve(rh.Point3d(*a), rh.Point3d(*b))
            model.Objects.AddCurve(line, _attributes(rh, index["node axes"], f"axis_{v + 1}", {"vertex": v}))
            counts["node axes"] += 1
    try:
        with atomic_path(path) as tmp:
            if not model.Write(str(tmp), 7):
                raise ExportError(f"{path}: rhino3dm could not write the file")
    except OSError as exc:
        raise ExportError(f"{path}: cannot write the .3dm file ({exc.strerror or exc})") from None
    return {"file": path.name, "bytes": path.stat().st_size, "objects": counts, "units": "mm",
            "seconds": time.perf_counter() - t0}


def read_3dm_parts(path) -> dict[str, dict]:
    """Objects of a ``.3dm`` file by name: ``{layer, vertices (n, 3), strings}`` (for checks and tests)."""
    import rhino3dm as rh

    model = rh.File3dm.Read(str(path))
    if model is None:
        raise ExportError(f"{path}: not a readable .3dm file")
    layers = [model.Layers[i].Name for i in range(len(model.Layers))]
    out: dict[str, dict] = {}
    for obj in model.Objects:
        a, geo = obj.Attributes, obj.Geometry
        item = {"layer": layers[a.LayerIndex], "strings": dict(a.GetUserStrings()), "type": type(geo).__name__}
        if isinstance(geo, rh.Mesh):
            item["vertices"] = np.array([[p.X, p.Y, p.Z] for p in geo.Vertices.ToPoint3dArray()])
            item["units"] = model.Settings.ModelUnitSystem
        out[a.Name] = item
    return out
