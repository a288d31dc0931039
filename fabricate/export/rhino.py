"""Rhino ``.3dm`` (rhino3dm): every part, the design mesh, the offset layers and the node axes.

Layers: ``glass``, ``steel`` (beams), ``nodes``, ``design mesh``, ``offset layers``,
``node axes``.  Every part is one closed mesh object named by its id (the
id of the STEP file and the bill of materials), its faces the part's planar
faces (quads kept, larger polygons as fans of triangles), its vertices
stored in double precision so they equal the STEP's; the bill-of-materials
row is attached as user strings (``kind``, ``element``, ``volume_mm3``,
``weight_kg``, ...).  Units: millimetres.  In Rhino, ``_MeshToNURB`` (or
``_ToPolysurface`` in Rhino 8) turns a part into a polysurface.

rhino3dm is imported here only.  It never frees an ``ObjectAttributes`` made in Python, nor the
geometry and attributes of a ``File3dmObject`` it hands out (which keep the model's own copies
alive): the writer reuses one attributes record for a file's objects, and :func:`read_3dm_parts`
reads in a child process, so that a long-lived process (a batch worker) keeps nothing of either.
"""
from __future__ import annotations

import logging
import os
import pickle
import subprocess
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Callable

from optimize.atomic import atomic_path
from optimize.errors import DISK_FULL, ExportError, c_errno, writing

if TYPE_CHECKING:
    import numpy as np

log = logging.getLogger(__name__)

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


def _attributes(rh) -> Callable[[int, str, dict], object]:
    """``set(layer, name, strings)``: one rhino3dm ObjectAttributes, given an object's layer, name and
    user strings (those of the object before removed) and returned, for ``Objects.Add*`` to copy.

    One record for the whole file: rhino3dm never frees one made in Python, so one per object kept
    about 3 kB an object (with its user strings) for the life of the process."""
    a = rh.ObjectAttributes()
    keys: list[str] = []

    def set_(layer: int, name: str, strings: dict) -> object:
        a.LayerIndex = layer
        a.Name = name
        for key in keys:
            if key not in strings:
                a.SetUserString(key, "")  # an empty value removes the key
        for key, value in strings.items():
            a.SetUserString(key, str(value))
        keys[:] = strings
        return a
    return set_


def write_3dm(parts, path, *, structure=None, mesh=None) -> dict:
    """Write ``parts`` (and the design ``mesh``, default ``parts.mesh``; when given, the ``structure``'s layers and node axes)
    as a Rhino 7 ``.3dm`` file in millimetres (atomic).  Returns facts: ``file, bytes, objects`` per layer."""
    import rhino3dm as rh

    from .meshes import require_finite

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
    attributes = _attributes(rh)
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
            model.Objects.AddMesh(_mesh(rh, g.vertices[i], faces), attributes(index[layer], pid, row))
            counts[layer] += 1
    if mesh is not None:
        model.Objects.AddMesh(_mesh(rh, mesh.V, mesh.F), attributes(index["design mesh"], "design", {}))
        counts["design mesh"] += 1
    if structure is not None:
        for i, d in enumerate(structure.distances):
            layer_mesh = structure.layer_mesh(i)
            model.Objects.AddMesh(_mesh(rh, layer_mesh.V, layer_mesh.F),
                                  attributes(index["offset layers"], f"layer_{i}", {"distance_mm": f"{d:g}"}))
            counts["offset layers"] += 1
        first, last = structure.layer_mesh(0).V, structure.layer_mesh(len(structure.distances) - 1).V
        for v, (a, b) in enumerate(zip(first.tolist(), last.tolist())):
            line = rh.LineCurve(rh.Point3d(*a), rh.Point3d(*b))
            model.Objects.AddCurve(line, attributes(index["node axes"], f"axis_{v + 1}", {"vertex": v}))
            counts["node axes"] += 1
    with writing(path, ".3dm file"), atomic_path(path) as tmp:
        c_errno(0)
        if not model.Write(str(tmp), 7):  # rhino3dm says only "failed": the C library's errno says why
            err = c_errno()
            if err in DISK_FULL:
                raise OSError(err, os.strerror(err), str(tmp))
            raise ExportError(f"{path}: rhino3dm could not write the file")
    return {"file": path.name, "bytes": path.stat().st_size, "objects": counts, "units": "mm",
            "seconds": time.perf_counter() - t0}


def read_3dm_parts(path) -> dict[str, dict]:
    """Objects of a ``.3dm`` file by name: ``{layer, type, strings, units, vertices (n, 3) float}``
    (vertices and units of meshes; for checks and tests).

    Read in a child process (:func:`_read_in_child`): each object rhino3dm hands to Python stays
    allocated, about 7 kB an object a read; in this process only when no child can be started."""
    import numpy as np

    objects = _read_in_child(path)
    if objects is None:
        objects = _read_objects(path)
    for item in objects.values():
        if "vertices" in item:
            item["vertices"] = np.frombuffer(item["vertices"], dtype=np.float64).reshape(-1, 3).copy()
    return objects


def _read_objects(path) -> dict[str, dict]:
    """:func:`read_3dm_parts`'s objects, read here, the vertices as the bytes of ``(n, 3) float64``."""
    import array

    import rhino3dm as rh

    model = rh.File3dm.Read(str(path))
    if model is None:
        raise ExportError(f"{path}: not a readable .3dm file")
    layers = [model.Layers[i].Name for i in range(len(model.Layers))]
    units = str(model.Settings.ModelUnitSystem)
    out: dict[str, dict] = {}
    for obj in model.Objects:
        a, geo = obj.Attributes, obj.Geometry
        item = {"layer": layers[a.LayerIndex], "strings": dict(a.GetUserStrings()), "type": type(geo).__name__}
        if isinstance(geo, rh.Mesh):
            item["vertices"] = array.array("d", [c for p in geo.Vertices.ToPoint3dArray()
                                                 for c in (p.X, p.Y, p.Z)]).tobytes()
            item["units"] = units
        out[a.Name] = item
    return out


def _read_in_child(path) -> dict[str, dict] | None:
    """:func:`_read_objects` of ``path`` in a child process (``python -c``, this package, no numpy);
    None when none can be started.  An unreadable file raises the child's ExportError; a child that
    fails otherwise (killed, a crash in rhino3dm) an ExportError naming the file and how it ended."""
    import fabricate

    root = str(Path(fabricate.__file__).resolve().parents[1])   # the child imports this very package
    code = f"import sys; sys.path.insert(0, {root!r}); from fabricate.export.rhino import _child; _child()"
    try:
        proc = subprocess.run([sys.executable, "-c", code, str(path)], stdin=subprocess.DEVNULL,
                              capture_output=True, check=False)
    except OSError as exc:
        log.warning("%s: read in this process (no child process: %s)", path, exc)
        return None
    answer = None
    if proc.returncode == 0:
        try:
            answer = pickle.loads(proc.stdout)
        except Exception:  # noqa: BLE001 - any undecodable answer is a failed read
            answer = None
    if isinstance(answer, dict) and isinstance(answer.get("objects"), dict):
        return answer["objects"]
    if isinstance(answer, dict) and isinstance(answer.get("error"), str):
        raise ExportError(answer["error"])
    how = f"signal {-proc.returncode}" if proc.returncode < 0 else f"exit {proc.returncode}"
    last = (proc.stderr.decode("utf-8", "replace").strip().splitlines() or ["no message"])[-1][:200]
    raise ExportError(f"{path}: rhino3dm could not read the file (its reader process ended with {how}: {last})")


def _child() -> None:
    """The child of :func:`_read_in_child`: ``PATH`` -> pickled ``{"objects": ...}`` or ``{"error": line}``."""
    try:
        answer = {"objects": _read_objects(sys.argv[1])}
    except ExportError as exc:
        answer = {"error": str(exc)}
    sys.stdout.buffer.write(pickle.dumps(answer, protocol=pickle.HIGHEST_PROTOCOL))
