"""``build_parts``: the offset stage's geometry in, panels, beams and nodes out (pure numpy).

Every part is a planar-faced solid built from planes (see ``panels``,
``beams``, ``nodes``); here the batches become :class:`PartGroup` objects
with ids, analytic volumes, flat outlines, neighbours, and are validated:
every face must be convex and turn the right way about its outward normal,
every volume positive.  A part that fails raises :class:`fabricate.cad.errors.PartError`
(a mesh fault: bad input) naming the part, its mesh element, the face and the setting to change.
"""
from __future__ import annotations

import logging

import numpy as np

from optimize.errors import ConfigError, MeshError

from .beams import BEVEL_FACE, FACE_NAMES, FACES, OUTLINE_FACE, RING, _face_centroids, beam_planes, beam_solids
from .errors import PartError
from .diagnose import CONVEX_MIN, beam_hint, min_turn, panel_failure
from .flat import flat_data
from .glass import overhead_limit
from .limits import check_limits
from .geometry import dot, polygon_area_2d, unit, volumes
from .hubs import tube_hubs
from .hubsize import hub_limit, size_hubs
from .nodes import node_solids
from .sections import BOX_FACES, BOX_NAMES, BOX_RING, MEMBERS as SECTION_MEMBERS, flange_plates
from .parts import PartGroup, Parts, part_ids, unit_id
from .spec import PartSpec

log = logging.getLogger(__name__)


def build_parts(structure, spec: PartSpec | None = None) -> Parts:
    """Panels (one per face), beams (one per edge) and nodes (one per vertex, if ``node_radius``).

    structure : :class:`fabricate.offset.OffsetStructure` (mm); the beams run
        between its first and last layer, the glass bears on the first layer
        and lies on the side away from the beams.
    spec : :class:`PartSpec` (default dimensions when None).
    Returns :class:`Parts`; the inputs are not modified.
    """
    spec = spec or PartSpec()
    d, P0, P1 = span_positions(structure)
    s_beam = 1.0 if d[-1] > d[0] else -1.0
    mode = spec.edge_mode(bool(structure.is_conical))
    mesh = structure.mesh
    topo = mesh.topology
    if len(structure.beam_quads) != len(topo.edges):
        raise MeshError(f"{mesh.name}: {len(structure.beam_quads)} beam quads for {len(topo.edges)} edges")
    pid = np.array(part_ids("panel", np.arange(mesh.n_faces)))
    bid = np.array(part_ids("beam", np.arange(len(topo.edges))))
    nid = np.array(part_ids("node", np.arange(mesh.n_vertices)))
    with_nodes = spec.connection == "hub"
    bp = beam_planes(structure)
    spec, sizing = size_hubs(structure, spec, P0, bp["normal"])  # no radius given: sized from the beam angles
    from .panels import panel_solids

    layers = spec.glass.solids()                      # outside in; the last one bears on the beams
    bearing = len(layers) - 1
    stack = tuple((ly.offset_mm, ly.thickness_mm, ly.inset_mm) for ly in layers)
    order = (bearing,) + tuple(range(bearing))        # the bearing ply first: it is checked as today

    def build(gap, edge_mode, faces=None):
        return panel_solids(structure, bp, P0, layers[bearing].thickness_mm, gap, edge_mode, s_beam, faces,
                            stack=tuple(stack[j] for j in order))

    batches = build(spec.joint_gap, mode)
    _check_panels(batches, pid, mesh, structure.normals, P0, spec, mode, build)
    groups = []
    multi = len(layers) > 1
    for j, ly in enumerate(layers):                    # one group per layer and face size
        for g in batches:
            f = g["faces_index"]
            ply = g["plies"][order.index(j)]
            ids = np.char.add(pid[f], f".{j + 1}") if multi else pid[f]
            touch = _touching(j, spec.glass)
            nb = [tuple(f"{u}.{k}" for k in touch) for u in pid[f].tolist()]
            if j == bearing:
                nb = [t + tuple(bid[row]) + (tuple(nid[mesh.F[i, :g["k"]]]) if with_nodes else ())
                      for t, i, row in zip(nb, f.tolist(), g["edges"])]
            groups.append(_group("panel", ids, f, ply["vertices"], g["faces"], ply["normals"], g["bearing_face"],
                                 1 - g["bearing_face"], g["planarity_mm"], np.full(len(f), ly.thickness_mm),
                                 np.zeros(len(f)), nb, spec, member=ly.member if multi else "",
                                 material="" if ly.material == "glass" else ly.material,
                                 hint=None if j == bearing else _ply_hint(ly, spec)))
    if multi:                                          # the beams carry the bearing ply
        pid = np.char.add(pid, f".{bearing + 1}")
    section = spec.beam.section
    web = spec.web if section != "plate" else spec.beam_width
    square = spec.connection != "mitre"
    beams = beam_solids(structure, P0, web, spec.end_setback, s_beam,
                        half_width=0.5 * max(web, spec.bearing_width), square=square)
    e = np.arange(len(topo.edges))
    Qb = bp["quad"]  # the beam's edge at the last layer as a fraction of it at the first (< 0: reversed)
    shrink = dot(Qb[:, 2] - Qb[:, 3], Qb[:, 1] - Qb[:, 0]) / np.maximum(dot(Qb[:, 1] - Qb[:, 0],
                                                                            Qb[:, 1] - Qb[:, 0]), 1e-300)
    X = beams["vertices"]
    along = unit(X[:, 1] - X[:, 0])
    proj = dot(X, along[:, None, :])
    length = proj.max(axis=1) - proj.min(axis=1)
    members = SECTION_MEMBERS[section]
    uid = lambda k: bid if section == "plate" else np.char.add(bid, f".{k}")  # noqa: E731
    nb = []
    for i, (fp, fm) in enumerate(beams["faces"].tolist()):
        others = [b for b in beams["neighbour_beams"][i].ravel().tolist() if b != i]
        nb.append(tuple(pid[sorted({fp, fm})]) + tuple(bid[sorted(set(others))])
                  + (tuple(nid[topo.edges[i]]) if with_nodes else ()))
    edge_mm = np.sqrt(dot(Qb[:, 1] - Qb[:, 0], Qb[:, 1] - Qb[:, 0]))
    hint = lambda i: beam_hint(float(beams["planarity_mm"][i]), web, float(shrink[i]),  # noqa: E731
                               abs(d[-1] - d[0]), length_mm=float(edge_mm[i]), setback_mm=spec.end_setback,
                               connection=spec.connection)
    centre = X[:, :4].copy()
    plates = []
    if section != "rhs":  # the plate, or the web of a tee / I
        _validate("beam", bid, e, X, FACES, beams["normals"], hint)
        plates.append((X, FACES, beams["normals"], OUTLINE_FACE, BEVEL_FACE, RING, web, "top"))
    for pl in flange_plates(beams["planes"], section, web, spec.beam.flange_mm, spec.beam.flange_width_mm):
        t = web if pl["member"].startswith("web") else spec.beam.flange_mm
        plates.append((pl["vertices"], BOX_FACES, pl["normals"], 0, 1, BOX_RING, t, "bottom"))
    side = beams["faces"].copy()
    edge_side = side[:, 0] == side[:, 1]     # a boundary beam: its one panel lies on one side of the plane
    on_plus = dot(_face_centroids(mesh)[side[:, 0]] - Qb[:, 0], bp["normal"]) >= 0
    side = np.where((edge_side & ~on_plus)[:, None], np.stack([np.full(len(e), -1), side[:, 1]], axis=1), side)
    side = np.where((edge_side & on_plus)[:, None], np.stack([side[:, 0], np.full(len(e), -1)], axis=1), side)
    for k, (member, (V, faces, normals, outline, bevel, ring, t, dashed)) in enumerate(zip(members, plates), 1):
        ids = uid(k)
        if section == "plate":
            near = nb
        else:  # a plate touches its unit's other plates, the panel on its side, the unit's neighbours
            sibs = tuple(f".{j}" for j in range(1, len(members) + 1) if j != k)
            which = (0 if "+" in member else 1) if member != "web" else None
            # what the glass bears on: the top flanges, and the web when it reaches under the panels
            glass = (member == "web" and web > spec.joint_gap) or member.startswith("top flange")
            near = [(tuple(pid[sorted({f for f in side[i] if f >= 0} if which is None else
                                      {f for f in side[i, which:which + 1] if f >= 0})]) if glass else ())
                    + tuple(bid[i] + s for s in sibs) + row[len(set(beams["faces"][i].tolist())):]
                    for i, row in enumerate(nb)]
        groups.append(_group("beam", ids, e, V, faces, normals, outline, bevel, beams["planarity_mm"],
                             np.full(len(e), float(t)), length, near, spec, ring=ring, dashed=dashed,
                             member=member, centre_line=centre, hint=hint))
    node_facts = {}
    if with_nodes:
        nodes = node_solids(structure, P0, P1, spec.hub_radius, spec.node_sides)
        v = np.arange(mesh.n_vertices)
        inc = [[] for _ in v]
        for i, (a, b) in enumerate(topo.edges.tolist()):  # incidence lists, built once
            inc[a].append(i)
            inc[b].append(i)
        nb = [tuple(bid[row]) for row in inc]
        diameter = np.full(len(v), 2 * spec.hub_radius)
        if spec.hub_kind == "solid":
            groups.append(_group("node", nid, v, nodes["vertices"], nodes["faces"], nodes["normals"], 0, 1,
                                 np.zeros(len(v)), diameter, nodes["length"], nb, spec))
        else:
            pieces = tube_hubs(nodes, spec.node.wall_mm, spec.node.cap_mm, nid, v)
            for k, pc in enumerate(pieces, 1):
                sibs = tuple(f".{j}" for j in range(1, len(pieces) + 1) if j != k)
                near = [row + tuple(nid[i] + s for s in sibs) for i, row in enumerate(nb)]
                groups.append(_group("node", np.char.add(nid, f".{k}"), v, pc["vertices"], pc["faces"],
                                     pc["normals"], 0, pc.get("back", 1), np.zeros(len(v)), pc["thickness"],
                                     pc["length"], near, spec,
                                     member=pc["member"]))
        node_facts = {"theta_max_deg": float(np.degrees(nodes["theta_max"].max())), "hub": spec.hub_kind,
                      "radius_mm": spec.hub_radius, "height_mm_min": float(nodes["length"].min()),
                      "height_mm_max": float(nodes["length"].max())}
        if spec.hub_kind == "tube":
            node_facts.update(wall_mm=spec.node.wall_mm, cap_mm=spec.node.cap_mm)
        node_facts["sizing"] = sizing
    report = _report(groups, spec, mode, s_beam, d, beams, node_facts)
    report["limits"] = check_limits(groups, spec)
    report["limits"].update(overhead_limit(groups, spec))  # a monolithic pane over people (fabricate.cad.glass)
    hub = hub_limit(structure, spec, sizing, P0, bp["normal"])
    if hub is not None:
        report["limits"]["hub"] = hub
    return Parts(groups=tuple(groups), spec=spec, edge_mode=mode, report=report, mesh=mesh)


def span_positions(structure) -> tuple[list[float], np.ndarray, np.ndarray]:
    """The beam span ``[d0, d1]`` and the vertex positions ``(n, 3)`` at ``d0`` (glass) and ``d1``.

    ``structure.beam_span`` when given (one distance ``d`` spans ``(0, d)``), else the
    first and last distance; positions ``V + d * axes / cos_theta`` (the layers).
    """
    span = getattr(structure, "beam_span", None)
    ds = [float(x) for x in structure.distances]
    d = [float(span[0]), float(span[1])] if span is not None else [ds[0], ds[-1]]
    if d[0] == d[1]:
        raise ConfigError(f"offset distances {ds}: the beams need two distinct layers, found span {d}")
    V = structure.mesh.V
    off = getattr(structure, "offset", None)
    if off is None:
        off = np.asarray(structure.axes, dtype=float) / np.asarray(structure.cos_theta, dtype=float)[:, None]
    return d, V + d[0] * off, V + d[1] * off


def _ply_hint(layer, spec):
    """The hint for a ply above the one on the beams that folds (its sides lean in with the height)."""
    text = (f"its {layer.member} lies {layer.offset_mm:g} to {layer.offset_mm + layer.thickness_mm:g} mm above "
            f"the bearing face of the build-up {spec.glass.short()} (parts.glass) and the panel's sides lean in: "
            "a thinner build-up, parts.edge: perpendicular or a smaller parts.joint_gap")
    return lambda i: text


def _touching(j: int, build_up) -> list[int]:
    """The solids (``k`` from 1) of a unit in contact with its solid ``j`` (0-based, outside in): the
    solid layers directly above and below it (none across the cavity)."""
    everything = build_up.layers()
    solid_at = [i for i, ly in enumerate(everything) if ly.solid]
    if len(solid_at) == 1:
        return []
    at = solid_at[j]
    return [solid_at.index(i) + 1 for i in (at - 1, at + 1) if 0 <= i < len(everything) and everything[i].solid]


def _group(kind, ids, element, V, faces, normals, outline, bevel, planarity, thickness, length,
           neighbours, spec, ring=None, dashed="bottom", member: str = "", centre_line=None,
           material: str = "", hint=None) -> PartGroup:
    """Validate one batch and derive volumes, outlines and residuals.

    ring : the outline's vertices (default the outline face's); dashed : which sheet face
    ``flat_bevel`` draws (``top`` for the beam plate: its + face; else the opposite face).
    """
    element = np.asarray(element)
    _validate(kind, ids, element, V, faces, normals, hint)
    vol = volumes(V, faces)
    bad = vol <= 0
    if bad.any():
        i = int(np.argmax(bad))
        raise PartError(f"{kind} {ids[i]} (element {int(element[i])}): volume {vol[i]:.6g} mm3, "
                        "expected a positive volume; check the parts dimensions", str(ids[i]), int(element[i]))
    residual = np.zeros(len(V))
    for fi, face in enumerate(faces):  # loop over the faces of one combinatorial type
        h = dot(V[:, list(face)], normals[:, fi][:, None, :])
        residual = np.maximum(residual, h.max(axis=1) - h.min(axis=1))
    ring = tuple(faces[outline]) if ring is None else tuple(ring)
    fd = flat_data(V, normals, faces, ring, outline, bevel)
    area = polygon_area_2d(fd["outline"])
    return PartGroup(kind=kind, ids=tuple(str(i) for i in ids), element=element, vertices=V, faces=tuple(faces),
                     normals=normals, volume_mm3=vol, outline_face=outline, bevel_face=bevel, flat=fd["outline"],
                     flat_bevel=fd["bottom_flat"] if dashed == "bottom" else fd["top_flat"], rect=fd["rect"],
                     bevel_ref=fd["ref"], bevel_ref_z=fd["ref_z"], bevel_deg=fd["bevel_deg"],
                     transform=fd["transform"],
                     flat_faces=(fd["top_flat"], fd["bottom_flat"]), cuts=fd["cuts"], ring=ring, area_mm2=area,
                     length_mm=np.asarray(length, dtype=float),
                     thickness_mm=np.asarray(thickness, dtype=float),
                     planarity_mm=np.asarray(planarity, dtype=float), residual_mm=residual,
                     neighbours=tuple(tuple(str(x) for x in nb) for nb in neighbours), member=member,
                     centre_line=centre_line, material=material)


HINTS = {"panel": "parts.joint_gap may be too large for this face, or the face is degenerate",
         "beam": "the beam may be shorter than its end trims: reduce parts.beam_width or parts.node_radius",
         "node": "parts.node_radius may be too large for the layer distance"}


def _validate(kind, ids, element, V, faces, normals, hint=None) -> None:
    """Raise PartError at the worst folded, reversed or collapsed face of the batch.

    hint : None (the kind's :data:`HINTS`) or ``hint(i) -> str`` for solid ``i``.
    """
    if not np.all(np.isfinite(V)):
        i = int(np.argwhere(~np.isfinite(V))[0, 0])
        raise PartError(f"{kind} {ids[i]} (element {int(element[i])}): a corner is not finite "
                        f"(parallel planes); {hint(i) if hint else HINTS[kind]}", str(ids[i]), int(element[i]))
    turn, where = min_turn(V, faces, normals)
    if (turn < CONVEX_MIN).any():
        i = int(np.argmin(turn))
        fi = int(where[i])
        if kind == "beam":
            name = FACE_NAMES[fi] if len(faces) == len(FACE_NAMES) else BOX_NAMES[fi]
        else:
            name = "lower" if fi == 0 else "upper" if fi == 1 else f"side {fi - 2}"
        raise PartError(f"{kind} {ids[i]} (element {int(element[i])}): face {name} is folded or "
                        f"collapsed (corner turn {turn[i]:.3g}, expected > 0); {hint(i) if hint else HINTS[kind]}",
                        str(ids[i]), int(element[i]))


def _check_panels(batches, pid, mesh, structure_normals, P0, spec, mode, build) -> None:
    """Raise the error of :func:`fabricate.cad.diagnose.panel_failure` when any panel folds."""
    bad = []  # (turn, face name, mesh face) of every failing panel
    for g in batches:
        turn, where = min_turn(g["vertices"], g["faces"], g["normals"])
        turn = np.where(np.isfinite(turn), turn, -np.inf)  # parallel planes count as folded
        for i in np.nonzero(turn < CONVEX_MIN)[0].tolist():  # the failing panels only
            fi = int(where[i])
            name = "lower" if fi == 0 else "upper" if fi == 1 else f"side {fi - 2}"
            bad.append((float(turn[i]), name, int(g["faces_index"][i])))
    if not bad:
        return
    bad.sort()
    turn, name, f = bad[0]
    P = P0[mesh.F[f, :mesh.face_sizes[f]]][None]
    faces = np.array([b[2] for b in bad])
    normal = np.asarray(structure_normals[f], dtype=float)
    raise panel_failure([pid[b[2]] for b in bad], faces, name, turn, P, normal, spec, mode, build)


def _report(groups, spec, mode, s_beam, distances, beams, node_facts) -> dict:
    """JSON-ready facts: counts, volumes, masses, worst planarity and residual, trims."""
    out: dict = {"edge_mode": mode, "glass_side": "opposite the beams",
                 "beams_toward": "+normal" if s_beam > 0 else "-normal",
                 "layers_mm": distances[:1] + distances[-1:]}
    for kind in ("panel", "beam", "node"):
        gs = [g for g in groups if g.kind == kind]
        if not gs:
            out[kind + "s"] = {"count": 0}
            continue
        vol = np.concatenate([g.volume_mm3 for g in gs])
        pl = np.concatenate([g.planarity_mm for g in gs])
        res = np.concatenate([g.residual_mm for g in gs])
        ids = [i for g in gs for i in g.ids]
        density = spec.density(kind)
        mass = sum(float(g.volume_mm3.sum()) * spec.group_density(g) for g in gs) * 1e-9
        out[kind + "s"] = {
            "count": int(len(vol)), "volume_mm3": float(vol.sum()), "mass_kg": mass,
            "density_kg_m3": density, "planarity_mm_max": float(pl.max()),
            "planarity_worst": ids[int(np.argmax(pl))],
            "residual_mm_max": float(res.max()), "residual_worst": ids[int(np.argmax(res))]}
    sb = beams["setback"]
    out["beams"]["end_setback_mm"] = {"min": float(sb.min()), "max": float(sb.max())}
    out["beams"]["bearing_width_mm"] = 0.5 * (spec.bearing_width - spec.joint_gap) - spec.glass.step_mm  # stepped unit
    out["beams"]["section"] = spec.beam.section
    out["beams"]["connection"] = spec.connection
    for kind in ("beam", "node"):
        units = {unit_id(i) for g in groups if g.kind == kind for i in g.ids}
        if units:
            out[kind + "s"]["units"] = len(units)
    out["beams"]["depth_mm"] = abs(distances[-1] - distances[0])
    panel_faces = [g.element for g in groups if g.kind == "panel"]
    units = int(len(np.unique(np.concatenate(panel_faces)))) if panel_faces else 0
    out["panels"].update(units=units, build_up=spec.glass.describe(), unit_thickness_mm=spec.glass.thickness_mm,
                         solids_per_unit=len(spec.glass.solids()))
    if node_facts:
        out["nodes"].update(node_facts)
    return out
