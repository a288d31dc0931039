"""Read the quad mesh of a Rhino ``.3dm`` file (rhino3dm; read only).

The mesh is one Mesh object of the file: the only one, or the one picked by
``layer`` (a layer name or full path ``Parent::Child``) and/or ``name`` (the
object's name).  Quads stay quads and triangles stay triangles; coordinates
are read in double precision, in the file's own model units: :func:`model_units`
says which (Rhino's ``ModelUnitSystem``) and the mesh's notes name it; the
application reads the file in that unit unless the config's ``units`` (or
``--units``) says otherwise.  rhino3dm does not expose Rhino's n-gon
records, so a mesh that Rhino shows with n-gons arrives as the quads and
triangles that make them up (said in the mesh's notes).

A file with no mesh object (only NURBS surfaces or polysurfaces) is refused
with the way out: in Rhino, ``_Mesh`` (or ``_QuadRemesh`` for a quad mesh)
on the surface, then save; a missing layer or name lists those that exist.
"""
from __future__ import annotations

import numpy as np

from .common import Parsed, fail

MAX_LISTED = 12

RHINO_UNIT_MM = {"Angstroms": 1e-7, "Nanometers": 1e-6, "Microns": 1e-3, "Millimeters": 1.0, "Centimeters": 10.0,
                 "Decimeters": 100.0, "Meters": 1000.0, "Dekameters": 1e4, "Hectometers": 1e5, "Kilometers": 1e6,
                 "Megameters": 1e9, "Gigameters": 1e12, "Microinches": 25.4e-6, "Mils": 25.4e-3, "Inches": 25.4,
                 "Feet": 304.8, "Yards": 914.4, "Miles": 1_609_344.0, "NauticalMiles": 1_852_000.0,
                 "PrinterPoints": 25.4 / 72, "PrinterPicas": 25.4 / 6}
"""Millimetres per unit of Rhino's length units (``rhino3dm.UnitSystem``); ``None``, ``Unset`` and
``CustomUnits`` have no entry (the file does not say a unit this reader trusts)."""


def _layer_names(model) -> list[str]:
    names = []
    for i in range(len(model.Layers)):
        layer = model.Layers[i]
        names.append(getattr(layer, "FullPath", None) or layer.Name)
    return names


def _listing(items) -> str:
    items = sorted(set(items))
    more = f" and {len(items) - MAX_LISTED} more" if len(items) > MAX_LISTED else ""
    return ", ".join(repr(x) for x in items[:MAX_LISTED]) + more if items else "none"


def _read(path: str):
    import rhino3dm as rh

    model = rh.File3dm.Read(str(path))
    if model is None:
        raise fail(path, None, "not a readable Rhino .3dm file (rhino3dm could not open it), "
                               "expected a file saved by Rhino 4-8")
    return model


def _unit_of(model) -> tuple[str, float | None]:
    system = model.Settings.ModelUnitSystem
    label = getattr(system, "name", str(system).rsplit(".", 1)[-1])
    return label, RHINO_UNIT_MM.get(label)


def model_units(path: str) -> tuple[str, float | None]:
    """``(name, mm per unit)`` of the model unit of the .3dm file ``path`` (Rhino's name, such as
    ``"Meters"``; mm per unit None when the file has no unit or a custom one)."""
    return _unit_of(_read(path))


def parse_3dm(path: str, *, layer: str | None = None, name: str | None = None) -> Parsed:
    """Parse ``path`` (a .3dm file) into :class:`Parsed` (faces 0-based; ``loc_kind`` ``object``)."""
    import rhino3dm as rh

    model = _read(path)
    layers = _layer_names(model)
    meshes, others = [], {}
    for obj in model.Objects:
        geo, a = obj.Geometry, obj.Attributes
        lname = layers[a.LayerIndex] if 0 <= a.LayerIndex < len(layers) else ""
        if isinstance(geo, rh.Mesh):
            meshes.append((lname, a.Name or "", geo))
        else:
            kind = type(geo).__name__
            others[kind] = others.get(kind, 0) + 1
    if not meshes:
        found = ", ".join(f"{n} {k}" for k, n in sorted(others.items())) or "no objects"
        raise fail(path, None, f"no mesh object in the file ({found}); expected a quad mesh: in Rhino "
                               "select the surface, run _Mesh (or _QuadRemesh for quads) and save, or "
                               "give the surface as input.surface exported as OBJ/STL")
    picked = meshes
    if layer is not None:
        picked = [m for m in picked if m[0] == layer or m[0].split("::")[-1] == layer]
        if not picked:
            raise fail(path, None, f"input.layer {layer!r}: no mesh on that layer; layers with meshes: "
                                   f"{_listing(m[0] for m in meshes)} (all layers: {_listing(layers)})")
    if name is not None:
        by_name = [m for m in picked if m[1] == name]
        if not by_name:
            raise fail(path, None, f"input.object {name!r}: no mesh of that name"
                                   f"{' on layer ' + repr(layer) if layer else ''}; named meshes: "
                                   f"{_listing(m[1] for m in picked if m[1])}")
        picked = by_name
    if len(picked) > 1:
        raise fail(path, None, f"{len(picked)} mesh objects match, expected one: pick one with input.object "
                               f"(names: {_listing(m[1] or '<unnamed>' for m in picked)}) or input.layer "
                               f"(layers: {_listing(m[0] for m in picked)})")
    lname, oname, geo = picked[0]
    pts = geo.Vertices.ToPoint3dArray()
    V = np.array([[p.X, p.Y, p.Z] for p in pts], dtype=np.float64).reshape(-1, 3)
    quads = np.array([tuple(geo.Faces[i]) for i in range(geo.Faces.Count)], dtype=np.int64).reshape(-1, 4)
    tri = quads[:, 2] == quads[:, 3]
    sizes = np.where(tri, 3, 4)
    keep = np.ones(quads.shape, dtype=bool)
    keep[tri, 3] = False
    label = f"mesh {oname!r} on layer {lname!r}" if oname else f"mesh on layer {lname!r}"
    unit, mm = _unit_of(model)
    notes = [f"{path}: read {label} ({len(V)} vertices, {len(sizes)} faces); the file's model unit: {unit}"
             + (f" ({mm:g} mm)" if mm is not None and unit != "Millimeters" else "")]
    return Parsed(V=V, flat=quads[keep], sizes=sizes, vertex_loc=np.zeros(len(V), dtype=np.int64),
                  face_loc=np.zeros(len(sizes), dtype=np.int64), loc_kind="object", notes=notes)
