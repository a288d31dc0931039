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

from .beams import BEVEL_FACE, FACE_NAMES, FACES, OUTLINE_FACE, RING, beam_planes, beam_solids
from .errors import PartError
from .diagnose import CONVEX_MIN, beam_hint, min_turn, panel_failure
from .flat import flat_data
from .limits import check_limits
from .geometry import dot, polygon_area_2d, unit, volumes
from .nodes import node_solids
from .parts import PartGroup, Parts, part_ids
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
    with_nodes = spec.node_radius > 0
    bp = beam_planes(structure)
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
    beams = beam_solids(structure, P0, spec.beam_width, spec.node_radius, s_beam)
    e = np.arange(len(topo.edges))
    Qb = bp["quad"]  # the beam's edge at the last layer as a fraction of it at the first (< 0: reversed)
    shrink = dot(Qb[:, 2] - Qb[:, 3], Qb[:, 1] - Qb[:, 0]) / np.maximum(dot(Qb[:, 1] - Qb[:, 0],
                                                                            Qb[:, 1] - Qb[:, 0]), 1e-300)
    X = beams["vertices"]
    along = unit(X[:, 1] - X[:, 0])
    proj = dot(X, along[:, None, :])
    nb = []
    for i, (fp, fm) in enumerate(beams["faces"].tolist()):
        others = [b for b in beams["neighbour_beams"][i].ravel().tolist() if b != i]
        nb.append(tuple(pid[sorted({fp, fm})]) + tuple(bid[sorted(set(others))])
                  + (tuple(nid[topo.edges[i]]) if with_nodes else ()))
    _validate("beam", bid, e, X, FACES, beams["normals"],
              lambda i: beam_hint(float(beams["planarity_mm"][i]), spec.beam_width, float(shrink[i]),
                                  abs(d[-1] - d[0])))
    groups.append(_group("beam", bid, e, X, FACES, beams["normals"], OUTLINE_FACE, BEVEL_FACE,
                         beams["planarity_mm"], np.full(len(e), spec.beam_width),
                         proj.max(axis=1) - proj.min(axis=1), nb, spec))
    node_facts = {}
    if with_nodes:
        nodes = node_solids(structure, P0, P1, spec.node_radius, spec.node_sides)
        v = np.arange(mesh.n_vertices)
        inc = [[] for _ in v]
        for i, (a, b) in enumerate(topo.edges.tolist()):  # incidence lists, built once
            inc[a].append(i)
            inc[b].append(i)
        nb = [tuple(bid[row]) for row in inc]
        groups.append(_group("node", nid, v, nodes["vertices"], nodes["faces"], nodes["normals"], 0, 1,
                             np.zeros(len(v)), np.full(len(v), 2 * spec.node_radius), nodes["length"], nb, spec))
        node_facts = {"theta_max_deg": float(np.degrees(nodes["theta_max"].max()))}
    report = _report(groups, spec, mode, s_beam, d, beams, node_facts)
    report["limits"] = check_limits(groups, spec)
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
           neighbours, spec, member: str = "", material: str = "", hint=None) -> PartGroup:
    """Validate one batch and derive volumes, outlines and residuals."""
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
    ring = RING if kind == "beam" else tuple(faces[outline])
    fd = flat_data(V, normals, faces, ring, outline, bevel)
    area = polygon_area_2d(fd["outline"])
    return PartGroup(kind=kind, ids=tuple(str(i) for i in ids), element=element, vertices=V, faces=tuple(faces),
                     normals=normals, volume_mm3=vol, outline_face=outline, bevel_face=bevel, flat=fd["outline"],
                     flat_bevel=fd["bottom_flat"] if kind != "beam" else fd["top_flat"], rect=fd["rect"],
                     bevel_ref=fd["ref"], bevel_ref_z=fd["ref_z"], bevel_deg=fd["bevel_deg"],
                     transform=fd["transform"],
                     flat_faces=(fd["top_flat"], fd["bottom_flat"]), cuts=fd["cuts"], ring=ring, area_mm2=area, length_mm=np.asarray(length, dtype=float),
                     thickness_mm=np.asarray(thickness, dtype=float),
                     planarity_mm=np.asarray(planarity, dtype=float), residual_mm=residual,
                     neighbours=tuple(tuple(str(x) for x in nb) for nb in neighbours), member=member,
                     material=material)


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
        name = FACE_NAMES[fi] if kind == "beam" else ("lower" if fi == 0 else "upper" if fi == 1
                                                      else f"side {fi - 2}")
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
    out["beams"]["bearing_width_mm"] = 0.5 * (spec.beam_width - spec.joint_gap) - spec.glass.step_mm  # stepped unit
    out["beams"]["depth_mm"] = abs(distances[-1] - distances[0])
    panel_faces = [g.element for g in groups if g.kind == "panel"]
    units = int(len(np.unique(np.concatenate(panel_faces)))) if panel_faces else 0
    out["panels"].update(units=units, build_up=spec.glass.describe(), unit_thickness_mm=spec.glass.thickness_mm,
                         solids_per_unit=len(spec.glass.solids()))
    if node_facts:
        out["nodes"].update(node_facts)
    return out
