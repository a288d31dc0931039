"""Every measure of a run with its tolerance, pass/fail and worst elements, relative and in mm.

``collect_measures(cfg, input, optimize, offset)`` returns ``{name: entry}``; an entry has ``unit``,
``max``, ``mean``, ``tolerance``, ``pass``, ``enforced`` (a failing enforced
measure makes the run "tolerance not reached", exit 3), ``worst`` (the five
worst elements with their index and value) and, where it means something,
the same figures in mm or degrees (``max_mm``, ``max_deg``).

Enforced: planarity always (glass panels are flat), and no folded panel (a
face the optimizer dented or flipped, ``optimize.mesh.measures.folded_faces``), and no offset face
that turns over (a layer past the focal distance, ``fabricate.offset.turnover``); the conical defect and
the planarity of the beams between interior nodes (torsion-free beams, the
paper's Geometry Fact 2) for a conical target; the circular defect for a
circular target.  Beams at boundary nodes are reported apart: there the faces
do not determine the node axis.  Closeness, the offset-distance error and the node-axis
defect are reported with their tolerance but do not change the exit code.
"""
from __future__ import annotations

import numpy as np

from optimize.mesh import measures as M
from optimize.mesh import Mesh

N_WORST = 5


def planarity_scale(mesh: Mesh) -> np.ndarray:
    """(m,) float: the length that makes planarity relative (mm): mean diagonal of a quad,
    mean edge length of an n-gon (0 for triangles)."""
    V, F, s = mesh.V, mesh.F, mesh.face_sizes
    out = np.zeros(mesh.n_faces)
    q = s == 4
    if q.any():
        Q = V[F[q, :4]]
        out[q] = 0.5 * (np.linalg.norm(Q[:, 2] - Q[:, 0], axis=1) + np.linalg.norm(Q[:, 3] - Q[:, 1], axis=1))
    for k in np.unique(s[s > 4]):
        sel = s == k
        P = V[F[sel, :k]]
        out[sel] = np.linalg.norm(np.roll(P, -1, axis=1) - P, axis=2).mean(axis=1)
    return out


def entry(values: np.ndarray, tolerance: float | None, unit: str, element: str, *,
          ids: np.ndarray | None = None, enforced: bool = False, extra: dict[str, np.ndarray] | None = None,
          what: str = "") -> dict:
    """Statistics of ``values (k,)`` with the ``N_WORST`` largest named by ``element`` index.

    ids : (k,) int element indices (default ``arange(k)``).
    extra : ``{"mm": (k,) values}`` reported as ``max_mm`` / ``mean_mm`` and per worst element.
    """
    values = np.asarray(values, dtype=float).ravel()
    ids = np.arange(values.size) if ids is None else np.asarray(ids).ravel()
    out = {"what": what, "unit": unit, "count": int(values.size), "tolerance": tolerance, "enforced": enforced}
    if values.size == 0:
        out.update(max=0.0, mean=0.0, worst=[], **{"pass": True})
        return out
    order = np.argsort(-values, kind="stable")[:N_WORST]
    worst = [{element: int(ids[i]), "value": float(values[i])} for i in order]
    for key, arr in (extra or {}).items():
        arr = np.asarray(arr, dtype=float).ravel()
        out[f"max_{key}"] = float(arr.max())
        out[f"mean_{key}"] = float(arr.mean())
        for w, i in zip(worst, order):
            w[key] = float(arr[i])
    out.update(max=float(values.max()), mean=float(values.mean()), worst=worst)
    out["pass"] = None if tolerance is None else bool(out["max"] <= tolerance)
    return out


ROUGHNESS_FLOOR = 0.01
"""Roughness (second difference over the mean edge) below which lines count as straight and evenly
spaced: added to both sides of :func:`roughness_ratio`, so a design of exactly straight lines (a
hyperbolic paraboloid's rulings) gives a finite ratio."""


def roughness_ratio(before: float, after: float) -> float:
    """How much rougher the result is than the input: ``(after + f) / (before + f)``,
    ``f`` = :data:`ROUGHNESS_FLOOR` (1: as fair as the design)."""
    return float((after + ROUGHNESS_FLOOR) / (before + ROUGHNESS_FLOOR))


def collect_measures(cfg, inp, opt, off) -> dict[str, dict]:
    """All measures of a run: ``cfg`` its RunConfig, ``inp``, ``opt``, ``off`` the records of its input,
    optimize and offset stages (:mod:`fabricate.app.records`)."""
    tol = cfg.tolerances.to_tolerances()
    mesh: Mesh = opt.mesh
    target = opt.target or inp.target  # a user's mesh may have fallen back to pq (fabricate.app.decide)
    topo = mesh.topology
    out: dict[str, dict] = {}

    plan = M.planarity(mesh)
    out["planarity"] = entry(plan, tol.planarity, "relative", "face", enforced=True,
                             extra={"mm": plan * planarity_scale(mesh)},
                             what="panel flatness: diagonal distance / mean diagonal (n-gons: plane distance / edge)")
    con = M.conical_defect(mesh)
    out["conical"] = entry(con, tol.conical, "rad", "vertex", ids=topo.interior_valence4,
                           enforced=target == "conical", extra={"deg": np.degrees(con)},
                           what="|w1 + w3 - w2 - w4| at interior valence-4 vertices")
    cir = M.circular_defect(mesh)
    out["circular"] = entry(cir, tol.circular, "rad", "face", ids=np.nonzero(mesh.face_sizes == 4)[0],
                            enforced=target == "circular", extra={"deg": np.degrees(cir)},
                            what="max(|phi1 + phi3 - pi|, |phi2 + phi4 - pi|) per quad")
    result = opt.result
    if result is not None:
        diag = inp.mesh.bbox_diagonal()  # the reference: the input in mm
        moved_mm = float(result.max_distance * diag)
        out["closeness"] = {
            "what": "max distance of a vertex to the reference surface / its bounding-box diagonal "
                    "(how far the design moved)",
            "unit": "relative", "count": mesh.n_vertices, "tolerance": tol.closeness, "enforced": False,
            "max": float(result.max_distance), "mean": None, "max_mm": moved_mm, "diagonal_mm": float(diag),
            "worst": [], "pass": bool(result.max_distance <= tol.closeness)}
        if tol.closeness_mm is not None:  # a limit in mm: closeness is then a requirement (apply_requirements)
            out["closeness"].update(tolerance_mm=float(tol.closeness_mm), **{"pass": moved_mm <= tol.closeness_mm})
        fair = (result.defects or {}).get("fairness")
        if fair is not None:
            ratio = roughness_ratio(fair["input"], fair["result"])
            out["roughness"] = {
                "what": "roughness of the result over the input's (mean second difference along the mesh lines "
                        f"over the mean edge, each plus {ROUGHNESS_FLOOR:g}; 1 = as fair as the design, above 1 "
                        "rougher)",
                "unit": "ratio", "count": mesh.n_vertices, "tolerance": tol.roughness, "enforced": False,
                "max": ratio, "mean": None, "input": float(fair["input"]),
                "result": float(fair["result"]), "worst": [], "pass": bool(ratio <= tol.roughness)}
        folded = (result.defects or {}).get("folded")
        if folded is not None:
            count = int(folded["count"])
            out["folded"] = {
                "what": "faces convex before the optimization that came out dented (a reflex corner) "
                        "or flipped: planar, but not a panel anyone can cut",
                "unit": "faces", "count": mesh.n_faces, "tolerance": 0, "enforced": True,
                "max": float(count), "mean": None,
                "worst": [{"face": int(f), "value": 1.0} for f in folded["faces"][:N_WORST]],
                "pass": count == 0}
        degenerate = [(k, (result.defects or {}).get(k)) for k in ("shrunk_edges", "straight_corners")]
        if any(d is not None for _, d in degenerate):
            faces = sorted({int(f) for _, d in degenerate if d for f in d.get("faces", [])})
            count = sum(int(d["count"]) for _, d in degenerate if d)
            out["degenerate"] = {
                "what": "faces with a side shrunk below 1 % of its input length (or 1e-6 of the face) or a corner "
                        "at 0 or 180 deg: planar, but a sliver no one can cut",
                "unit": "faces", "count": mesh.n_faces, "tolerance": 0, "enforced": True,
                "max": float(count), "mean": None,
                **{k: (d or {}).get("count", 0) for k, d in degenerate},
                "worst": [{"face": f, "value": 1.0} for f in faces[:N_WORST]], "pass": count == 0}
    out.update(_offset_measures(off.structure, mesh, tol, enforce=target == "conical"))
    return out


ID_KINDS = {"face": "panel", "beam": "beam", "vertex": "node"}
"""The part kind whose id names a worst element of each kind (face -> P0007, beam -> B0226, vertex -> N0012)."""


def name_worst(measures: dict, mesh: Mesh) -> dict:
    """Add the part id (``P0007``, ``B0226``, ``N0012``: the ids of every file) to each worst element
    of ``measures`` (face, beam (edge) or vertex index of ``mesh``), as ``id``.  Returns ``measures``."""
    from fabricate.cad.parts import part_ids

    counts = {"face": mesh.n_faces, "beam": len(mesh.topology.edges), "vertex": mesh.n_vertices}
    for m in measures.values():
        for w in m.get("worst") or ():
            elem = next((k for k in ID_KINDS if k in w), None)
            if elem is not None and "id" not in w:
                w["id"] = part_ids(ID_KINDS[elem], np.array([int(w[elem]), counts[elem] - 1]))[0]
    return measures


def _turned_entry(t: dict) -> dict:
    """Faces of an offset layer that turn over (``fabricate.offset.turnover``): enforced, none allowed."""
    worst = [{"face": f, "value": 1.0, "distance_mm": L["distance_mm"]}
             for L in t["per_layer"] for f in L["faces"]][:N_WORST]
    return {"what": "offset faces that turn over (a layer past the focal distance of its faces: "
                    "panels and beams cross); safe range of distances " + _range(t["safe_range_mm"]),
            "unit": "faces", "count": int(t["faces"]), "tolerance": 0, "enforced": True,
            "max": float(t["count"]), "mean": None, "worst": worst, "per_layer": t["per_layer"],
            "safe_range_mm": t["safe_range_mm"], "pass": bool(t["ok"])}


def _range(r) -> str:
    lo, hi = r
    def mm(x, sign=""):  # millimetres as a shop reads them: 85,320 mm, 0.24 mm, never 8.532e+04
        return f"{x:{sign},.0f}" if abs(x) >= 100 else f"{x:{sign}.3g}"

    return f"{'-inf' if lo is None else mm(lo)} .. {'+inf' if hi is None else mm(hi, '+')} mm"


def _offset_measures(s, mesh: Mesh, tol, enforce: bool) -> dict[str, dict]:
    if s is None:
        return {}
    out = {}
    d = np.abs(np.asarray(s.distances, dtype=float))
    err = np.abs(np.asarray(s.face_distance_error, dtype=float))  # (m, L) mm
    if err.size:
        rel = np.where(d[None, :] > 0, err / np.where(d > 0, d, 1.0)[None, :], 0.0)
        out["offset_distance"] = entry(rel.max(axis=1), tol.offset, "relative", "face",
                                       extra={"mm": err.max(axis=1)},
                                       what="distance error of the offset faces / their offset distance "
                                            "(reported; exact only where the mesh is conical)")
    twist = np.asarray(s.beam_twist_mm, dtype=float)
    if twist.size:
        rel = M.quad_planarity(np.asarray(s.beam_quads, dtype=float))
        deg = np.asarray(s.beam_twist_deg, dtype=float)
        edges = np.asarray(s.edges)
        at_boundary = mesh.topology.is_boundary_vertex[edges].any(axis=1)
        for key, sel, enforced, what in (
                ("beam_planarity", ~at_boundary, enforce,
                 "flatness (torsion) of the beams between interior nodes: diagonal distance / mean diagonal"),
                ("beam_planarity_boundary", at_boundary, False,
                 "the same for beams at boundary nodes, where the faces leave the node axis free "
                 "(reported: a least-squares choice of axes, not exact in general)")):
            ids = np.nonzero(sel)[0]
            out[key] = entry(rel[ids], tol.beam_planarity, "relative", "beam", ids=ids, enforced=enforced,
                             extra={"twist_mm": twist[ids], "twist_deg": np.abs(deg[ids])}, what=what)
    turned = (s.report or {}).get("turned_over")
    if turned is not None:
        out["offset_turned_over"] = _turned_entry(turned)
    axis = np.asarray(s.axis_defect, dtype=float)
    if axis.size:
        out["axis_defect"] = entry(axis, None, "rad", "vertex", extra={"deg": np.degrees(axis)},
                                   what="spread of the angle between the node axis and the face normals")
    return out


def warnings(measures: dict, limits: dict | None = None) -> list[str]:
    """One line per information measure beyond its tolerance, with its value in mm where it has one
    (not the defect of a target the run did not ask for: ``role`` reported), and per shop limit
    (``parts.report["limits"]``) some part breaks, with the ids."""
    out = []
    for name, m in measures.items():
        if m.get("enforced") or m.get("pass") is not False or m.get("role") == "reported":
            continue
        mm = next((m[k] for k in ("max_mm", "max_twist_mm") if m.get(k) is not None), None)
        deg = m.get("max_deg")
        top = m.get("max")
        top = float("nan") if top is None else top  # a non-finite figure reads back from JSON as null
        value = (f"{mm:.3g} mm" if mm is not None else f"{deg:.3g} deg" if deg is not None
                 else f"{top:.3g} {m.get('unit', '')}".strip())
        out.append(f"{name} {value} (max {top:.3g} {m.get('unit', '')} > tolerance {m['tolerance']:.3g})")
    for key, v in (limits or {}).items():
        if v.get("count"):
            ids = ", ".join(v["ids"][:12]) + (" ..." if v["count"] > 12 else "")
            out.append(f"{v['count']} part(s) beyond the {key} limit ({v['limit']}): {ids}")
    return out
