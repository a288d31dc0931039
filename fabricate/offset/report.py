"""The per-element tolerance report of the offset stage (JSON-ready, model units = mm).

What a facade engineer checks, each with its tolerance and the worst
elements named by index and vertices: input planarity per face, node-axis
defect per vertex, offset-distance error and spread per face and layer, beam
twist per edge (mm and degrees), plus the spherical image and focal points as
analysis.  ``summary`` holds the plain sentences printed by the CLI; a mesh
that is not conical is said to be so, with the numbers.
"""
from __future__ import annotations

import numpy as np

from optimize.mesh.measures import conical_defect
from optimize.mesh import Mesh
from optimize.tolerances import Tolerances

from .beams import beam_planarity
from .focal import axis_line_intersections, edge_families, spherical_image_defect
from .turnover import turnover_report, turnover_sentence

WORST = 5
"""How many worst elements each section names."""


def _top(values: np.ndarray, k: int = WORST) -> np.ndarray:
    """Indices of the ``k`` largest finite values, largest first."""
    v = np.where(np.isfinite(values), values, -np.inf)
    idx = np.argsort(-v, kind="stable")[: min(k, len(v))]
    return idx[np.isfinite(values[idx])]


def _face(mesh: Mesh, f: int) -> list[int]:
    return mesh.F[f][mesh.F[f] >= 0].tolist()


def _stats(x: np.ndarray) -> dict:
    x = x[np.isfinite(x)]
    if x.size == 0:
        return {"max": 0.0, "mean": 0.0}
    return {"max": float(x.max()), "mean": float(x.mean())}


def offset_report(mesh: Mesh, distances: tuple, span: tuple, a: dict, *, tol: Tolerances,
                  is_pq: bool, is_conical: bool, flip: bool, axes_source: str,
                  straighten: dict | None) -> dict:
    """Build the report from the arrays of :func:`fabricate.offset.offset_structure`.

    ``a`` holds ``normals (m,3), axes (n,3), cos_theta (n,), axis_defect (n,),
    edges (e,2), beam_quads (e,4,3), beam_twist_mm (e,), beam_twist_deg (e,),
    face_distance_error (m,L), face_distance_spread (m,L), planarity (m,), offset (n,3)``.
    """
    t = mesh.topology
    plan = a["planarity"]
    defect = a["axis_defect"]
    err, spread = a["face_distance_error"], a["face_distance_spread"]
    mm, deg = a["beam_twist_mm"], a["beam_twist_deg"]
    bplan = beam_planarity(a["beam_quads"])
    edges = a["edges"]
    theta = np.degrees(np.arccos(np.clip(a["cos_theta"], -1.0, 1.0)))
    con = conical_defect(mesh)
    con_v = t.interior_valence4

    rel = np.zeros_like(err)
    nz = np.array([d != 0 for d in distances])
    rel[:, nz] = err[:, nz] / np.abs(np.asarray(distances, dtype=float)[nz])[None, :]
    per_layer = []
    for i, d in enumerate(distances):
        f = int(np.argmax(err[:, i]))
        per_layer.append({"distance_mm": d, "max_error_mm": float(err[:, i].max()),
                          "mean_error_mm": float(err[:, i].mean()), "max_relative": float(rel[:, i].max()),
                          "max_spread_mm": float(spread[:, i].max()), "worst_face": f})
    face_err = err.max(axis=1)
    worst_layer = err.argmax(axis=1)
    max_rel = float(rel.max())

    sph = spherical_image_defect(mesh, a["normals"])
    focal, _, gap = axis_line_intersections(mesh.V, a["axes"], edges)
    fam = edge_families(mesh)
    boundary_edge = t.is_boundary_vertex[edges].all(axis=1)

    status = "conical" if is_conical else ("pq_not_conical" if is_pq else "not_pq")
    rep = {
        "stage": "offset",
        "units": "mm",
        "mesh": {"name": mesh.name, "vertices": mesh.n_vertices, "faces": mesh.n_faces,
                 "edges": int(len(edges)), "bbox_diagonal_mm": mesh.bbox_diagonal()},
        "distances_mm": list(distances),
        "beam_span_mm": list(span),
        "flip": bool(flip),
        "axes_source": axes_source,
        "status": status,
        "is_pq": is_pq,
        "is_conical": is_conical,
        "tolerances": tol.as_dict(),
        "planarity": {**_stats(plan), "tolerance": tol.planarity, "ok": is_pq,
                      "worst": [{"face": int(f), "vertices": _face(mesh, f), "planarity": float(plan[f])}
                                for f in _top(plan)]},
        "conical_defect_rad": {**_stats(con), "count": int(con.size), "tolerance": tol.conical,
                               "ok": bool(con.max(initial=0.0) <= tol.conical),
                               "worst": [{"vertex": int(con_v[i]), "rad": float(con[i])} for i in _top(con)]},
        "axis_defect_rad": {**_stats(defect),
                            "worst": [{"vertex": int(v), "rad": float(defect[v]),
                                       "deg": float(np.degrees(defect[v])),
                                       "faces": t.star_faces[v][t.star_faces[v] >= 0].tolist()}
                                      for v in _top(defect)]},
        "cone_angle_deg": {"max": float(theta.max()), "mean": float(theta.mean()),
                           "worst_vertex": int(np.argmax(theta))},
        "face_distance": {"max_error_mm": float(err.max()), "max_spread_mm": float(spread.max()),
                          "max_relative": max_rel, "tolerance_relative": tol.offset,
                          "ok": bool(max_rel <= tol.offset), "per_layer": per_layer,
                          "worst": [{"face": int(f), "vertices": _face(mesh, f),
                                     "distance_mm": distances[int(worst_layer[f])],
                                     "error_mm": float(face_err[f]),
                                     "spread_mm": float(spread[f, worst_layer[f]])}
                                    for f in _top(face_err)]},
        "beams": {"count": int(len(edges)), "span_mm": list(span),
                  "max_twist_mm": float(mm.max()), "mean_twist_mm": float(mm.mean()),
                  "max_twist_deg": float(np.abs(deg).max()), "max_planarity": float(bplan.max()),
                  "steepest_edge": int(np.argmax(np.abs(deg))) if len(deg) else None,
                  "tolerance": tol.beam_planarity, "ok": bool(bplan.max() <= tol.beam_planarity),
                  "boundary_max_twist_mm": float(mm[boundary_edge].max(initial=0.0)),
                  "interior_max_twist_mm": float(mm[~boundary_edge].max(initial=0.0)),
                  "worst": [{"edge": int(e), "vertices": edges[e].tolist(), "twist_mm": float(mm[e]),
                             "twist_deg": float(deg[e]), "planarity": float(bplan[e])}
                            for e in _top(mm)]},
        "turned_over": turnover_report(mesh, a["normals"], a["offset"], distances),
        "free_axes": straighten,
        "spherical_image": {"quads": int(sph.size), "degenerate": int(np.isnan(sph).sum()),
                            **_stats(sph), "tolerance": tol.circular,
                            "worst_vertex": (int(con_v[_top(sph)[0]]) if np.isfinite(sph).any() else None)},
        "focal": {"finite_points": int(np.isfinite(focal).all(axis=1).sum()),
                  "max_axis_gap_mm": float(gap.max()),
                  "two_families": bool((fam >= 0).all())},
    }
    rep["summary"] = _sentences(rep, mesh)
    return rep


def _sentences(r: dict, mesh: Mesh) -> list[str]:
    """Plain statements for people (printed by ``fabricate offset``)."""
    out = []
    turned = turnover_sentence(r["turned_over"])
    if turned:
        out.append(turned)
    fd, bm, ax, pl = r["face_distance"], r["beams"], r["axis_defect_rad"], r["planarity"]
    if not r["is_pq"]:
        w = pl["worst"][0]
        out.append(f"NOT PQ: face {w['face']} has planarity {w['planarity']:.3g} "
                   f"(tolerance {pl['tolerance']:g}); panels cannot be flat, offsets are approximate.")
    if r["is_conical"]:
        out.append(f"Conical mesh: node axes exact within {ax['max']:.3g} rad; every offset face lies "
                   f"at its distance within {fd['max_error_mm']:.3g} mm; beams planar within "
                   f"{bm['max_twist_mm']:.3g} mm.")
    else:
        cd = r["conical_defect_rad"]
        w = ax["worst"][0] if ax["worst"] else {"vertex": None, "rad": 0.0, "deg": 0.0}
        balance = (f"angle balance |w1+w3-w2-w4| up to {cd['max']:.3g} rad at vertex "
                   f"{cd['worst'][0]['vertex']} (tolerance {cd['tolerance']:g}); " if cd["worst"] else "")
        out.append(f"NOT CONICAL: the faces at a vertex do not touch one cone ({balance}face angles about "
                   f"the axis spread up to {w['deg']:.3g} deg at vertex {w['vertex']}); "
                   "node axes are least-squares fits.")
        wf = fd["worst"][0] if fd["worst"] else None
        if wf is not None:
            out.append(f"Offset faces are off their distance by up to {fd['max_error_mm']:.3g} mm "
                       f"(face {wf['face']} at {wf['distance_mm']:g} mm; spread up to "
                       f"{fd['max_spread_mm']:.3g} mm, relative {fd['max_relative']:.3g}).")
    we = bm["worst"][0] if bm["worst"] else None
    if we is not None and not bm["ok"]:
        steep = bm.get("steepest_edge")
        angle = (f"; the steepest twist {bm['max_twist_deg']:.3g} deg is at edge {steep}"
                 if steep is not None and steep != we["edge"] else "")
        out.append(f"Beams twist up to {bm['max_twist_mm']:.3g} mm "
                   f"(edge {we['edge']} {we['vertices']}: {we['twist_mm']:.3g} mm, "
                   f"{we['twist_deg']:.3g} deg){angle}; "
                   f"beam planarity tolerance {bm['tolerance']:g}.")
    return out
