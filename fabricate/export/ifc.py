"""IFC4 of every part: the coordination model a BIM tool opens.

Structure of the file::

    IfcProject -> IfcSite -> IfcBuilding  (IfcRelAggregates)
    IfcBuilding contains one IfcCurtainWall (IfcRelContainedInSpatialStructure)
    IfcCurtainWall aggregates
        one IfcPlate  (CURTAIN_PANEL) per glass unit    P0001 ...  (its plies P0001.1 ... as the
                                                                 items of one body representation)
        one IfcMember (MULLION)       per beam          B0001 ...  (a section's plates B0001.1 ...
                                                                 as the items of its body)
        one IfcMember (USERDEFINED 'NODE') per node hub N0001 ...  (a tube hub: tube and caps)

``Name`` and ``Tag`` of every element are the part id of the STEP file and
the bill of materials.  Geometry is exact: every part is a planar-faced
polyhedron, written as a closed ``IfcPolygonalFaceSet`` (IFC4's faceted
solid: the part's own vertices in millimetres, one indexed planar polygon per
face, a hub tube's annular ends ``IfcIndexedPolygonalFaceWithVoids``; a quarter of the entities
of an ``IfcFacetedBrep``); a glass unit of several solids
(laminated, insulated) has one face set per ply and interlayer in its one body.  Materials:
the glass as an ``IfcMaterialLayerSet`` listing the build-up from the outside in (every
glass ply, interlayer (PVB, SGP) and the cavity's gas, ``IsVentilated`` false), the steel
as an ``IfcMaterial`` with its grade.
Quantities: ``Qto_PlateBaseQuantities`` (width = thickness, gross/net area,
volume, weight) and ``Qto_MemberBaseQuantities`` (length, volume, weight);
the fabrication figures (planarity of a panel, twist of a beam, construction
residual, all in mm) in the property set ``Pset_ConicalFabFabrication``.

Writing: ifcopenshell makes the file's skeleton (header, project, site,
building, curtain wall, units, contexts, materials); the per-part entities
(face sets, elements, placements, property and quantity sets, relationships)
follow as Part 21 text generated in bulk by :mod:`fabricate.export.ifc_text`,
their ids continuing the skeleton's (one template per group of solids of the
same topology), about ten times faster than creating each entity through
ifcopenshell.  ifcopenshell is imported here only: the rest of the pipeline
starts without it.

Threads: ifcopenshell keeps process-wide state that one call changes for all threads
(``ifcopenshell.validate`` switches the feature ``use_attribute_value_derived`` on and back to what
it found, so two validations at once leave it on, or switch it off under the other one, whose
file then fails with "Attribute is derived in subtype"; its log is one per process too).  Every
use of ifcopenshell in this package runs under :func:`ifcopenshell_alone`: a batch's jobs in the
threads of one Dask worker write and check their IFC files one at a time.
"""
from __future__ import annotations

import contextlib
import os
import threading
import time
from pathlib import Path

from optimize.atomic import atomic_open
from optimize.errors import ExportError

from .meshes import require_finite

PSET = "Pset_ConicalFabFabrication"
CLASS = {"panel": ("IfcPlate", "CURTAIN_PANEL", None),
         "beam": ("IfcMember", "MULLION", None),
         "node": ("IfcMember", "USERDEFINED", "NODE")}
DERIVED = "use_attribute_value_derived"
"""ifcopenshell's process-wide feature that ``ifcopenshell.validate`` switches on while it runs
(off: an attribute a subtype derives (``*``) reads as None)."""
_LOCK = threading.RLock()


@contextlib.contextmanager
def ifcopenshell_alone():
    """Hold ifcopenshell for this thread: every other thread's ifcopenshell work in this package
    waits (re-entrant: a check that opens the file through :func:`open_ifc` holds it once more).
    Hold it as long as the files it made or opened are read, not only while they are parsed: their
    attributes read through the same process-wide switches.  On leaving, :data:`DERIVED` is as it
    was on entering, even when ifcopenshell raised half-way (``validate`` restores it only when it
    returns)."""
    with _LOCK:
        from ifcopenshell import ifcopenshell_wrapper

        before = ifcopenshell_wrapper.get_feature(DERIVED)
        try:
            yield
        finally:
            ifcopenshell_wrapper.set_feature(DERIVED, before)


def _skeleton(name: str, grade: str, spec):
    """The file's skeleton made by ifcopenshell: project, site, building, curtain wall, units, the
    representation context and its Body subcontext, the materials.  Returns ``(file, refs)``, refs the
    ids :func:`fabricate.export.ifc_text.write_body` refers to."""
    import ifcopenshell
    import ifcopenshell.guid

    guid = ifcopenshell.guid.new
    f = ifcopenshell.file(schema="IFC4")
    origin = f.createIfcAxis2Placement3D(f.createIfcCartesianPoint((0.0, 0.0, 0.0)), None, None)
    context = f.createIfcGeometricRepresentationContext(None, "Model", 3, 1.0e-5, origin, None)
    body = f.createIfcGeometricRepresentationSubContext(
        "Body", "Model", None, None, None, None, context, None, "MODEL_VIEW", None)
    units = _units(f)
    project = f.createIfcProject(guid(), None, name, "conical-fab model", None, None, None, [context], units)
    site = f.createIfcSite(guid(), None, "Site", None, None, f.createIfcLocalPlacement(None, origin), None, None,
                           "ELEMENT", None, None, None, None, None)
    building = f.createIfcBuilding(guid(), None, "Building", None, None,
                                   f.createIfcLocalPlacement(site.ObjectPlacement, origin),
                                   None, None, "ELEMENT", None, None, None)
    f.createIfcRelAggregates(guid(), None, None, None, project, [site])
    f.createIfcRelAggregates(guid(), None, None, None, site, [building])
    wall_place = f.createIfcLocalPlacement(building.ObjectPlacement, origin)
    wall = f.createIfcCurtainWall(guid(), None, "Roof", "glass roof on torsion-free beams", None,
                                  wall_place, None, "CW", "USERDEFINED")
    wall.ObjectType = "conical-mesh glass roof"
    f.createIfcRelContainedInSpatialStructure(guid(), None, None, None, [wall], building)
    steel = f.createIfcMaterial(grade, "structural steel", "steel")
    _density(f, steel, spec.density_steel)
    layers = _glass_layers(f, spec)
    return f, {"body": body.id(), "origin": origin.id(), "wall_place": wall_place.id(), "wall": wall.id(),
               "layers": layers.id(), "steel": steel.id()}


def _units(f) -> object:
    """The model's ``IfcUnitAssignment``: mm, m2, m3, kg, rad."""
    return f.createIfcUnitAssignment([
        f.createIfcSIUnit(None, "LENGTHUNIT", "MILLI", "METRE"),
        f.createIfcSIUnit(None, "AREAUNIT", None, "SQUARE_METRE"),
        f.createIfcSIUnit(None, "VOLUMEUNIT", None, "CUBIC_METRE"),
        f.createIfcSIUnit(None, "MASSUNIT", "KILO", "GRAM"),
        f.createIfcSIUnit(None, "PLANEANGLEUNIT", None, "RADIAN")])


def _glass_layers(f, spec) -> object:
    """The glass build-up as an ``IfcMaterialLayerSet``: one layer per ply, interlayer and cavity, outside in."""
    build_up = spec.glass
    made: dict[str, object] = {}

    def material(name: str):
        if name not in made:
            if name == "glass":
                made[name] = f.createIfcMaterial("Glass", "float glass", "glass")
                _density(f, made[name], spec.density_glass)
            elif name in ("PVB", "SGP"):
                made[name] = f.createIfcMaterial(name, f"{name} interlayer", "plastic")
                _density(f, made[name], spec.density("panel", name))
            else:
                made[name] = f.createIfcMaterial(name.capitalize(), f"{name} filling of the cavity", "gas")
        return made[name]

    layers = [f.createIfcMaterialLayer(material(ly.material), float(ly.thickness_mm), False, ly.member or "ply 1",
                                       None, ly.material if ly.solid else "cavity", None)
              for ly in build_up.layers()]
    return f.createIfcMaterialLayerSet(layers, build_up.describe()[:255], None)


def _density(f, material, density: float) -> None:
    prop = f.createIfcPropertySingleValue("MassDensity", None, f.createIfcMassDensityMeasure(float(density)), None)
    f.createIfcMaterialProperties("Pset_MaterialCommon", None, [prop], material)


def write_ifc(parts, path, *, grade: str | None = None, project: str = "conical-fab") -> dict:
    """Write ``parts`` as IFC4 (atomic).  Returns facts: ``file, bytes, elements`` per kind, ``seconds``.

    grade : steel grade written as the beams' and nodes' material name (default: the parts' steel_grade).
    """
    from .ifc_text import write_body

    t0 = time.perf_counter()
    require_finite(parts)
    grade = grade or getattr(parts.spec, "steel_grade", "S355")
    path = Path(path)
    try:
        with ifcopenshell_alone():
            f, refs = _skeleton(project, grade, parts.spec)
            head, first_id = f.to_string(), max(e.id() for e in f) + 1
    except ImportError as exc:  # a declared dependency; only a broken install lands here
        raise ExportError(f"{path}: ifcopenshell is not available ({exc}); expected it installed") from None
    end = head.rindex("ENDSEC;", 0, head.rindex("END-ISO-10303-21;"))
    groups = list(parts.groups)
    index = {id(g): k for k, g in enumerate(groups)}
    solids = _solids_by_unit(parts)
    units = _glass_units(parts, solids, index) + _steel_units(parts, solids, index)
    try:
        with atomic_open(path, "w", encoding="utf-8") as fh:
            fh.write(head[:end])
            write_body(fh, groups, [_faces(g) for g in groups], units, refs, first_id, PSET)
            fh.write(head[end:])
    except OSError as exc:
        raise ExportError(f"{path}: cannot write the IFC file ({exc.strerror or exc})") from None
    elements = {k: sum(u.kind == k for u in units) for k in CLASS}
    return {"file": path.name, "bytes": path.stat().st_size, "schema": "IFC4",
            "elements": elements, "seconds": time.perf_counter() - t0}


def _unit(kind: str, uid: str, description: str, solids: list, quantities: dict, props: dict):
    from .ifc_text import Unit

    cls, predefined, object_type = CLASS[kind]
    qto_name = "Qto_PlateBaseQuantities" if kind == "panel" else "Qto_MemberBaseQuantities"
    return Unit(kind, cls.upper(), predefined, object_type, uid, description, solids, qto_name, quantities, props)


def _amounts(volume_m3: float, weight: float) -> dict:
    """The volume and weight quantities of an element (gross = net: no openings)."""
    return {"GrossVolume": ("volume", volume_m3), "NetVolume": ("volume", volume_m3),
            "GrossWeight": ("weight", weight), "NetWeight": ("weight", weight)}


def _solids_by_unit(parts) -> dict[tuple[str, str], list]:
    """``{(kind, unit id): [(group, i)]}``: the solids of each element, in the groups' order (a glass
    unit's plies and interlayers, a beam's plates, a hub's tube and caps; else the part alone)."""
    from fabricate.cad.parts import unit_id

    out: dict[tuple[str, str], list] = {}
    for g in parts.groups:
        for i, pid in enumerate(g.ids):
            out.setdefault((g.kind, unit_id(pid)), []).append((g, i))
    return out


def _glass_units(parts, solids: dict, index: dict) -> list:
    """One IfcPlate per glass unit: its ply on the beams gives area and planarity, every ply and
    interlayer (``solids``: :func:`_solids_by_unit`) a face set of its body; volume and weight summed
    over them."""
    from fabricate.cad.glass import bearing_groups
    from fabricate.cad.parts import unit_id

    spec = parts.spec
    density = {id(g): spec.group_density(g) for g in parts.of_kind("panel")}
    out = []
    for g in bearing_groups(parts):
        for i, ply in enumerate(g.ids):  # one element per unit
            uid = unit_id(ply)
            items = solids["panel", uid]
            volume_m3 = sum(float(h.volume_mm3[k]) for h, k in items) * 1e-9
            weight = sum(float(h.volume_mm3[k]) * density[id(h)] for h, k in items) * 1e-9
            area = float(g.area_mm2[i]) * 1e-6
            fab = {"PartId": uid, "MeshElement": int(g.element[i]), "BuildUp": spec.glass.short(),
                   "Solids": " ".join(f"{uid}.{k + 1}" for k in range(len(items))) if len(items) > 1 else uid,
                   "Residual_mm": float(g.residual_mm[i]), "Planarity_mm": float(g.planarity_mm[i]),
                   "Neighbours": " ".join(n for n in g.neighbours[i] if unit_id(n) != uid)}
            if spec.glass.type == "insulated":
                fab["SpacerSetback_mm"] = float(spec.glass.edge_seal_mm)
            out.append(_unit("panel", uid, "glass unit " + spec.glass.short(), [(index[id(h)], k) for h, k in items],
                             {"Width": ("length", spec.glass.thickness_mm), "GrossArea": ("area", area),
                              "NetArea": ("area", area), **_amounts(volume_m3, weight)}, fab))
    return out


def _steel_units(parts, solids: dict, index: dict) -> list:
    """One IfcMember per beam and per node hub: a beam welded from plates, a hub of tube and caps is
    one element of one face set per solid (``solids``: :func:`_solids_by_unit`)."""
    out = []
    for (kind, uid), items in solids.items():
        if kind == "panel":
            continue
        g, i = items[0]
        quantities, fab = _describe(g, i, parts.spec.group_density(g), items if len(items) > 1 else None, parts.spec)
        out.append(_unit(kind, uid, kind, [(index[id(h)], k) for h, k in items], quantities, fab))
    return out


def _describe(g, i: int, density: float, unit=None, spec=None) -> tuple[dict, dict]:
    """``(quantities, fabrication figures)`` of beam or node part ``i`` of group ``g``; ``unit``:
    ``[(group, i)]`` of every solid of a unit of several (a beam's plates, a hub's tube and caps):
    volumes and weights summed, the solids listed.  (Glass units: :func:`_glass_units`.)"""
    from fabricate.cad.parts import unit_id

    volume_m3 = float(g.volume_mm3[i]) * 1e-9
    weight = volume_m3 * density
    fab = {"PartId": g.ids[i], "MeshElement": int(g.element[i]),
           "Residual_mm": float(g.residual_mm[i]), "Neighbours": " ".join(g.neighbours[i])}
    if unit is not None:
        uid = unit_id(g.ids[i])
        volume_m3 = sum(float(h.volume_mm3[k]) for h, k in unit) * 1e-9
        weight = sum(float(h.volume_mm3[k]) * spec.group_density(h) for h, k in unit) * 1e-9
        near = {n for h, k in unit for n in h.neighbours[k] if unit_id(n) != uid}
        fab.update(PartId=uid, Solids=" ".join(h.ids[k] for h, k in unit), Neighbours=" ".join(sorted(near)),
                   Residual_mm=max(float(h.residual_mm[k]) for h, k in unit))
    fab["Twist_mm" if g.kind == "beam" else "Planarity_mm"] = float(g.planarity_mm[i])
    return {"Length": ("length", g.length_mm[i]), **_amounts(volume_m3, weight)}, fab


def _faces(group) -> tuple:
    """The faces of a group's solids in IFC: a hub tube's ends are one annulus each, a face with a hole
    (as in STEP: :func:`fabricate.export.step.step_faces`); every other part its polygons."""
    from .step import step_faces

    return step_faces(group)[0]


def open_ifc(path):
    """``ifcopenshell.open`` of ``path``; a file it cannot read or parse is an :class:`ExportError`
    naming it (ifcopenshell's own errors are not).  Call it, and read the file it returns, inside
    :func:`ifcopenshell_alone`."""
    import ifcopenshell

    try:
        with ifcopenshell_alone():
            return ifcopenshell.open(str(path))
    except (OSError, ifcopenshell.Error) as exc:
        raise ExportError(f"{path}: not a readable IFC file ({exc}); expected the model.ifc of a run") from None


def read_ifc(path) -> dict[str, dict]:
    """Elements of an IFC file written by :func:`write_ifc`: id -> ``{class, predefined, volume_mm3}``.

    The volume comes from ifcopenshell's own geometry kernel (the triangulated
    face set), so it checks the file independently of the writer.
    """
    with ifcopenshell_alone():
        return _read_ifc(path)


def _read_ifc(path) -> dict[str, dict]:
    import ifcopenshell
    import ifcopenshell.geom
    import ifcopenshell.util.shape

    f = open_ifc(path)
    elements = {e.GlobalId: e for e in f.by_type("IfcElement") if not e.is_a("IfcCurtainWall")}
    out: dict[str, dict] = {}
    if not elements:
        return out
    settings = ifcopenshell.geom.settings()
    it = ifcopenshell.geom.iterator(settings, f, max(1, os.cpu_count() or 1), include=list(elements.values()))
    if it.initialize():
        while True:
            shape = it.get()
            el = elements[shape.guid]
            # geometry comes back in metres (SI) whatever the file's length unit
            out[el.Name] = {"class": el.is_a(), "predefined": el.PredefinedType, "tag": el.Tag,
                            "volume_mm3": float(ifcopenshell.util.shape.get_volume(shape.geometry)) * 1e9}
            if not it.next():
                break
    for el in elements.values():  # an element the kernel could not make a shape of: no volume
        out.setdefault(el.Name, {"class": el.is_a(), "predefined": el.PredefinedType, "tag": el.Tag,
                                 "volume_mm3": float("nan")})
    return out
