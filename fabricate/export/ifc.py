"""IFC4 of every part: the coordination model a BIM tool opens.

Structure of the file::

    header: FILE_DESCRIPTION ViewDefinition [ReferenceView_V1.2]; FILE_NAME with author, organization,
            preprocessor and originating system conical-fab <version>
    IfcProject -> IfcSite -> IfcBuilding -> IfcBuildingStorey  (IfcRelAggregates)
    IfcBuildingStorey contains one IfcCurtainWall (IfcRelContainedInSpatialStructure)
    IfcCurtainWall aggregates
        one IfcPlate  (CURTAIN_PANEL) per glass unit    P0001 ...  (its plies P0001.1 ... as the
                                                                 items of one body representation)
        one shop assembly per shipping piece of several solids, an IfcElementAssembly (FACTORY):
            a beam welded from plates (GIRDER)      B0001   aggregating an IfcPlate (SHEET) per plate B0001.1 ...
            a tube hub (USERDEFINED 'NODE')         N0001   aggregating its tube N0001.1 (IfcMember MEMBER)
                                                            and caps N0001.2, N0001.3 (IfcPlate SHEET)
        one IfcMember (MULLION) per plate beam          B0001 ...
        one IfcMember (USERDEFINED 'NODE') per solid hub N0001 ...

``Name`` and ``Tag`` of every element are the part id of the STEP file and
the bill of materials.  Geometry is exact: every part is a planar-faced
polyhedron, written as a closed ``IfcPolygonalFaceSet`` (IFC4's faceted
solid: the part's own vertices in millimetres, one indexed planar polygon per
face, a hub tube's annular ends ``IfcIndexedPolygonalFaceWithVoids``; a quarter of the entities
of an ``IfcFacetedBrep``); a glass unit of several solids
(laminated, insulated) has one face set per ply and interlayer in its one body; an assembly has no
body of its own (its parts, placed relative to it, have theirs).  Materials:
the glass as an ``IfcMaterialLayerSet`` listing the build-up from the outside in (every
glass ply, interlayer (PVB, SGP) and the cavity's gas, ``IsVentilated`` false), the steel
as an ``IfcMaterial`` with its grade (plates and caps), the standard sections as
``IfcMaterialProfileSet`` s of it (:func:`_profiles`: the beams' section on a beam assembly or plate
beam, the CHS on a hub tube, the round bar on a solid hub).
Quantities: ``Qto_PlateBaseQuantities`` (width = thickness, gross/net area,
volume, weight), ``Qto_MemberBaseQuantities`` and, on an assembly, :data:`ASSEMBLY_QTO` (length, volume,
weight).  Every steel piece's length is the steel cut list's (one length per beam: its plates' cut
outlines along its axis, as the NC1 file); the cut list's figures (``part_id``, ``type``, ``assembly``,
``member``, ``section``, ``grade``, ``length_mm``, ``system_length_mm``) and the fabrication figures
(planarity of a panel, twist of a beam, construction residual, all in mm) are in the property set
:data:`PSET`.

Writing: ifcopenshell makes the file's skeleton (header, project, site,
building, storey, curtain wall, units, contexts, materials, profiles); the per-part entities
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

PSET = "ConicalFab_Fabrication"
"""The project's property set: the cut list's figures (id, type, assembly, member, section, grade,
length_mm, system_length_mm) and the fabrication figures (planarity, twist, residual in mm)."""
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


def _skeleton(name: str, grade: str, parts, filename: str = "model.ifc", author: str = "",
              organization: str = ""):
    """The file's skeleton made by ifcopenshell: header, project, site, building, storey, curtain wall,
    units, the representation context and its Body subcontext, the materials (glass layer set, steel, the
    profile sets of :func:`_profiles`).  Returns ``(file, refs)``, refs the ids
    :func:`fabricate.export.ifc_text.write_body` refers to."""
    import ifcopenshell
    import ifcopenshell.guid

    guid = ifcopenshell.guid.new
    f = ifcopenshell.file(schema="IFC4")
    _header(f, filename, author, organization)
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
    storey = f.createIfcBuildingStorey(guid(), None, "Roof", "the roof's level: every part in model coordinates",
                                       None, f.createIfcLocalPlacement(building.ObjectPlacement, origin),
                                       None, None, "ELEMENT", 0.0)
    f.createIfcRelAggregates(guid(), None, None, None, project, [site])
    f.createIfcRelAggregates(guid(), None, None, None, site, [building])
    f.createIfcRelAggregates(guid(), None, None, None, building, [storey])
    wall_place = f.createIfcLocalPlacement(storey.ObjectPlacement, origin)
    wall = f.createIfcCurtainWall(guid(), None, "Roof", "glass roof on torsion-free beams", None,
                                  wall_place, None, "CW", "USERDEFINED")
    wall.ObjectType = "conical-mesh glass roof"
    f.createIfcRelContainedInSpatialStructure(guid(), None, None, None, [wall], storey)
    steel = f.createIfcMaterial(grade, "structural steel", "steel")
    _density(f, steel, parts.spec.density_steel)
    layers = _glass_layers(f, parts.spec)
    refs = {"body": body.id(), "origin": origin.id(), "wall_place": wall_place.id(), "wall": wall.id(),
            "layers": layers.id(), "steel": steel.id()}
    for key, (profile, label) in _profiles(f, parts).items():
        mp = f.createIfcMaterialProfile(Name=label, Material=steel, Profile=profile)
        refs[key] = f.createIfcMaterialProfileSet(Name=label, MaterialProfiles=[mp]).id()
    return f, refs


VIEW = "ViewDefinition [ReferenceView_V1.2]"
"""The file's model view (IFC4 Reference View: tessellated bodies, assemblies, material profile sets)."""


def _header(f, filename: str, author: str, organization: str) -> None:
    """FILE_DESCRIPTION (:data:`VIEW`) and FILE_NAME: the file's name, author and organization (as given;
    empty: not known), ``conical-fab <version>`` as preprocessor and originating system (with the
    ifcopenshell that wrote the skeleton), no authorization."""
    import ifcopenshell

    from fabricate import __version__

    f.header.file_description.description = (VIEW,)
    fn = f.header.file_name
    fn.name = filename
    fn.author = (author,)
    fn.organization = (organization,)
    fn.preprocessor_version = f"conical-fab {__version__}"
    fn.originating_system = f"conical-fab {__version__} (ifcopenshell {ifcopenshell.version})"
    fn.authorization = "none"


def beam_depth(parts) -> float:
    """The beams' depth (mm), glass bearing to the last layer: the section's nominal height."""
    import numpy as np

    return float(abs(np.diff(parts.report.get("layers_mm", [0.0, parts.spec.beam_depth]))[0]))


def _profiles(f, parts) -> dict[str, tuple]:
    """The standard sections of the steel: ``{refs key: (profile def, name)}``: ``profile`` the beams'
    section (plate: ``IfcRectangleProfileDef`` width x depth; tee ``IfcTShapeProfileDef``, I
    ``IfcIShapeProfileDef``, RHS ``IfcRectangleHollowProfileDef`` (wall: the web; the name gives web / flange
    when they differ)), ``tube`` a tube hub's ``IfcCircleHollowProfileDef`` (CHS), ``hub`` a solid hub's
    ``IfcCircleProfileDef`` (RD).  The name is the cut list's section text; the bodies stay the exact
    faceted solids."""
    from fabricate.cad.sections import section_text

    from .schedules import hub_section

    spec = parts.spec
    out = {}
    if parts.of_kind("beam"):
        b, depth = spec.beam, beam_depth(parts)
        name = section_text(spec, depth)
        tw, tf, w = spec.web, float(b.flange_mm), float(b.flange_width_mm)
        if b.section == "plate":
            p = f.createIfcRectangleProfileDef("AREA", name, None, float(spec.beam_width), depth)
        elif b.section == "rhs":
            p = f.createIfcRectangleHollowProfileDef("AREA", name, None, w, depth, tw, None, None)
        elif b.section == "tee":
            p = f.createIfcTShapeProfileDef("AREA", name, None, depth, w, tw, tf, None, None, None, None, None)
        else:
            p = f.createIfcIShapeProfileDef("AREA", name, None, w, depth, tw, tf, None, None, None)
        out["profile"] = (p, name)
    if parts.of_kind("node") and spec.hub_radius > 0:
        _, piece = hub_section(spec)
        r = float(spec.hub_radius)
        if spec.hub_kind == "tube":
            out["tube"] = (f.createIfcCircleHollowProfileDef("AREA", piece, None, r, float(spec.node.wall_mm)), piece)
        else:
            out["hub"] = (f.createIfcCircleProfileDef("AREA", piece, None, r), piece)
    return out


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


def write_ifc(parts, path, *, grade: str | None = None, project: str = "conical-fab", author: str = "",
              organization: str = "") -> dict:
    """Write ``parts`` as IFC4 (atomic).  Returns facts: ``file, bytes, elements`` (top-level pieces per
    kind), ``assemblies``, ``seconds``.

    grade : steel grade written as the beams' and nodes' material name (default: the parts' steel_grade).
    author, organization : the header's FILE_NAME (empty: not known).
    """
    from .ifc_text import write_body

    t0 = time.perf_counter()
    require_finite(parts)
    grade = grade or getattr(parts.spec, "steel_grade", "S355")
    path = Path(path)
    try:
        with ifcopenshell_alone():
            f, refs = _skeleton(project, grade, parts, path.name, author, organization)
            head, first_id = f.to_string(), max(e.id() for e in f) + 1
    except ImportError as exc:  # a declared dependency; only a broken install lands here
        raise ExportError(f"{path}: ifcopenshell is not available ({exc}); expected it installed") from None
    end = head.rindex("ENDSEC;", 0, head.rindex("END-ISO-10303-21;"))
    groups = list(parts.groups)
    units = ifc_units(parts, grade, refs)
    try:
        with atomic_open(path, "w", encoding="utf-8") as fh:
            fh.write(head[:end])
            write_body(fh, groups, [_faces(g) for g in groups], units, refs, first_id, PSET)
            fh.write(head[end:])
    except OSError as exc:
        raise ExportError(f"{path}: cannot write the IFC file ({exc.strerror or exc})") from None
    elements = {k: sum(u.kind == k for u in units) for k in CLASS}
    return {"file": path.name, "bytes": path.stat().st_size, "schema": "IFC4", "elements": elements,
            "assemblies": sum(bool(u.parts) for u in units), "seconds": time.perf_counter() - t0}


def ifc_units(parts, grade: str, refs: dict) -> list:
    """Every element of the file as :class:`fabricate.export.ifc_text.Unit` records (solids by index into
    ``parts.groups``): the glass units, then the steel shipping pieces (:func:`_steel_units`).  ``refs``:
    the skeleton's materials (which profile sets exist)."""
    index = {id(g): k for k, g in enumerate(parts.groups)}
    solids = _solids_by_unit(parts)
    types = _types(parts)
    return _glass_units(parts, solids, index, types) + _steel_units(parts, solids, index, grade, refs, types)


def _unit(kind: str, uid: str, description: str, solids: list, quantities: dict, props: dict,
          cls: tuple | None = None, qto: str | None = None, material: str = "steel", parts=()):
    from .ifc_text import Unit

    cls_name, predefined, object_type = cls or CLASS[kind]
    qto_name = qto or ("Qto_PlateBaseQuantities" if kind == "panel" else "Qto_MemberBaseQuantities")
    return Unit(kind, cls_name.upper(), predefined, object_type, uid, description, solids, qto_name, quantities,
                props, material, list(parts))


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


def _types(parts) -> dict[str, str]:
    """The schedules' ``type`` of every glass unit, beam and hub (``G007``, ``BT012``, ``NT003``): unit
    id -> type name."""
    from .schedules import beam_types, glass_types, node_types

    out: dict[str, str] = {}
    for kind, types in (("panel", glass_types), ("beam", beam_types), ("node", node_types)):
        if parts.of_kind(kind):
            ids, names, _ = types(parts)
            out.update(zip(ids, names))
    return out


def _glass_units(parts, solids: dict, index: dict, types: dict) -> list:
    """One IfcPlate per glass unit: its ply on the beams gives area and planarity, every ply and
    interlayer (``solids``: :func:`_solids_by_unit`) a face set of its body; volume and weight summed
    over them; ``types``: :func:`_types`."""
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
            fab = {"part_id": uid, "type": types.get(uid, ""), "build_up": spec.glass.short(),
                   "solids": " ".join(f"{uid}.{k + 1}" for k in range(len(items))) if len(items) > 1 else uid,
                   "mesh_element": int(g.element[i]), "residual_mm": float(g.residual_mm[i]),
                   "planarity_mm": float(g.planarity_mm[i]),
                   "neighbours": " ".join(n for n in g.neighbours[i] if unit_id(n) != uid)}
            if spec.glass.type == "insulated":
                fab["spacer_setback_mm"] = float(spec.glass.edge_seal_mm)
            out.append(_unit("panel", uid, "glass unit " + spec.glass.short(), [(index[id(h)], k) for h, k in items],
                             {"Width": ("length", spec.glass.thickness_mm), "GrossArea": ("area", area),
                              "NetArea": ("area", area), **_amounts(volume_m3, weight)}, fab, material="layers"))
    return out


ASSEMBLY = {"beam": ("IfcElementAssembly", "GIRDER", None), "node": ("IfcElementAssembly", "USERDEFINED", "NODE")}
"""A shipping piece welded in the shop from several solids: a beam of plates, a tube hub of tube and caps."""
PLATE = ("IfcPlate", "SHEET", None)
TUBE = ("IfcMember", "MEMBER", None)
ASSEMBLY_QTO = "ConicalFab_AssemblyQuantities"
"""The quantities of an assembly (length, volume, weight): IFC4 has no base quantity set for one."""


def system_lengths(parts) -> dict[int, float]:
    """Per beam (mesh edge) its length node axis to node axis (mm): the mesh edge, else its centre line
    (the steel cut list's ``system_length_mm``)."""
    import numpy as np

    from .schedules import unit_facts

    topo = parts.mesh.topology if parts.mesh is not None else None
    if topo is not None:
        ends = parts.mesh.V[topo.edges]
        return dict(enumerate(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1).tolist()))
    return dict(enumerate(unit_facts(parts)["length"].tolist()))


def _steel_units(parts, solids: dict, index: dict, grade: str, refs: dict, types: dict) -> list:
    """The steel's shipping pieces: a beam or hub of one solid is one IfcMember (its section's profile set
    as material); one of several solids (a beam welded from plates, a tube hub of tube and caps) is one
    IfcElementAssembly (the profile set of the beam's section) aggregating an IfcPlate (SHEET) per plate
    or cap and an IfcMember per tube (the CHS profile set).  Every piece's ``Length`` (quantity and
    ``length_mm``) is the steel cut list's: a beam's the extent of its plates' cut outlines along its axis
    (:func:`fabricate.export.schedules.beam_lengths`), a hub's its height (tube and caps), a part's its
    own; ``types``: :func:`_types`."""
    from .schedules import beam_lengths, hub_section

    spec = parts.spec
    if not (parts.of_kind("beam") or parts.of_kind("node")):
        return []
    plate_length, beam_length = beam_lengths(parts)
    system = system_lengths(parts) if parts.of_kind("beam") else {}
    beam_section = _profile_name(parts) if parts.of_kind("beam") else ""
    hub_text, piece = hub_section(spec)
    out = []
    for (kind, uid), items in solids.items():
        if kind == "panel":
            continue
        g, i = items[0]
        beam = kind == "beam"
        length = beam_length[uid] if beam else sum(float(h.length_mm[k]) for h, k in items)   # a hub: its height
        between = {"system_length_mm": system[int(g.element[i])]} if beam else {}
        q, fab = _describe(g, i, spec.group_density(g), items if len(items) > 1 else None, spec)
        q["Length"] = ("length", length)
        fab = {"part_id": uid, "type": types.get(uid, ""), "assembly": uid, "member": "beam" if beam else "hub",
               "section": beam_section if beam else hub_text, "grade": grade, "length_mm": length, **between, **fab}
        solid = [(index[id(h)], k) for h, k in items]
        if len(items) == 1:
            own = "profile" if beam else ("hub" if "hub" in refs else "steel")
            out.append(_unit(kind, uid, kind, solid, q, fab, material=own if own in refs else "steel"))
            continue
        pieces = []
        for (h, k), one in zip(items, solid):
            pid = h.ids[k]
            tube = h.member == "tube"
            pq, pfab = _describe(h, k, spec.group_density(h), None, spec)
            own_length = plate_length[pid] if beam else float(h.length_mm[k])
            pfab = {"part_id": pid, "type": types.get(uid, ""), "assembly": uid, "member": h.member,
                    "section": piece if tube else f"PL{h.thickness_mm[k]:g}", "grade": grade,
                    "length_mm": own_length, **between, **pfab}
            if tube:
                pq["Length"] = ("length", own_length)
                pieces.append(_unit(kind, pid, f"{kind} {h.member}", [one], pq, pfab, cls=TUBE,
                                    material="tube" if "tube" in refs else "steel"))
                continue
            area = float(h.area_mm2[k]) * 1e-6
            pq = {"Width": ("length", float(h.thickness_mm[k])), "GrossArea": ("area", area), "NetArea": ("area", area),
                  **{key: v for key, v in pq.items() if key != "Length"}}
            pieces.append(_unit(kind, pid, f"{kind} {h.member}", [one], pq, pfab, cls=PLATE,
                                qto="Qto_PlateBaseQuantities"))
        what = f"beam {beam_section}" if beam else hub_text
        out.append(_unit(kind, uid, what, [], q, fab, cls=ASSEMBLY[kind], qto=ASSEMBLY_QTO,
                         material="profile" if beam and "profile" in refs else "steel", parts=pieces))
    return out


def _profile_name(parts) -> str:
    from fabricate.cad.sections import section_text

    return section_text(parts.spec, beam_depth(parts))


def _describe(g, i: int, density: float, unit=None, spec=None) -> tuple[dict, dict]:
    """``(quantities, fabrication figures)`` of beam or node part ``i`` of group ``g``; ``unit``:
    ``[(group, i)]`` of every solid of a unit of several (a beam's plates, a hub's tube and caps):
    volumes and weights summed, the solids listed.  (Glass units: :func:`_glass_units`; the length:
    :func:`_steel_units`.)"""
    from fabricate.cad.parts import unit_id

    volume_m3 = float(g.volume_mm3[i]) * 1e-9
    weight = volume_m3 * density
    fab = {"mesh_element": int(g.element[i]), "residual_mm": float(g.residual_mm[i]),
           "neighbours": " ".join(g.neighbours[i])}
    if unit is not None:
        uid = unit_id(g.ids[i])
        volume_m3 = sum(float(h.volume_mm3[k]) for h, k in unit) * 1e-9
        weight = sum(float(h.volume_mm3[k]) * spec.group_density(h) for h, k in unit) * 1e-9
        near = {n for h, k in unit for n in h.neighbours[k] if unit_id(n) != uid}
        fab.update(solids=" ".join(h.ids[k] for h, k in unit), neighbours=" ".join(sorted(near)),
                   residual_mm=max(float(h.residual_mm[k]) for h, k in unit))
    fab["twist_mm" if g.kind == "beam" else "planarity_mm"] = float(g.planarity_mm[i])
    return {"Length": ("length", float(g.length_mm[i])), **_amounts(volume_m3, weight)}, fab


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
    """Elements of an IFC file written by :func:`write_ifc` (its assemblies left out: their parts are
    elements): id -> ``{class, predefined, tag, volume_mm3}``.

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
    elements = {e.GlobalId: e for e in f.by_type("IfcElement")     # an assembly's body is its parts'
                if not e.is_a("IfcCurtainWall") and not e.is_a("IfcElementAssembly")}
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
