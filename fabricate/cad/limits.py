"""Shop limits: corner angles, edge lengths, panel size against the stock sheet, panel weight.

Measured on the flat data (``PartGroup.bevel_ref``: the panel's bearing face,
the beam's profile, a hub cap's outline; ``rect``: the stock rectangle), vectorized per group.
"""
from __future__ import annotations

import numpy as np

from .parts import cut_from_sheet


def corner_angles_deg(Q: np.ndarray) -> np.ndarray:
    """(p, k) interior angles (degrees) of counter-clockwise 2D polygons ``Q (p, k, 2)``."""
    e_in = Q - np.roll(Q, 1, axis=1)
    e_out = np.roll(Q, -1, axis=1) - Q
    cross = e_in[..., 0] * e_out[..., 1] - e_in[..., 1] * e_out[..., 0]
    dot = (e_in * e_out).sum(axis=2)
    return 180.0 - np.degrees(np.arctan2(cross, dot))


def edge_lengths(Q: np.ndarray) -> np.ndarray:
    """(p, k) lengths of edge ``j -> j + 1`` of polygons ``Q (p, k, d)``."""
    return np.linalg.norm(np.roll(Q, -1, axis=1) - Q, axis=2)


def min_widths(Q: np.ndarray) -> np.ndarray:
    """(p,) the smallest width of convex polygons ``Q (p, k, 2)``: the least extent across an edge
    (a regular ``k``-gon of circumradius ``r``: ``2 r cos(pi / k)`` across flats for even ``k``)."""
    E = np.roll(Q, -1, axis=1) - Q
    n = np.stack([-E[..., 1], E[..., 0]], axis=2) / np.linalg.norm(E, axis=2)[..., None]
    h = np.einsum("pvi,pki->pkv", Q, n)                    # every vertex across every edge
    return (h.max(axis=2) - h.min(axis=2)).min(axis=1)


def check_limits(groups, spec) -> dict:
    """Parts beyond ``spec.limits``: ``{limit: {"limit", "count", "ids", "worst", "worst_id"}}`` (JSON-ready).

    ``corner``: panels and hub cap plates with a corner below ``min_corner_deg``; ``edge``: panels and
    beams with an outline edge below ``min_edge_mm``, hub cap plates narrower than it (a cap's edges
    are the facets of a round plate, ``2 r sin(pi / K)``: 20.9 mm for a 24-gon D160, so it is held by its
    width, as a flange by its edges along the beam); ``sheet``: panels whose stock rectangle does not fit the
    sheet ``sheet_mm`` either way round (per glass ply); ``weight``: glass units (every ply and interlayer)
    heavier than ``max_panel_kg``, by unit id.
    """
    lim = spec.limits
    W, H = lim.sheet_mm
    found: dict[str, list] = {"corner": [], "edge": [], "sheet": [], "weight": []}
    unit_kg: dict[str, float] = {}
    for g in groups:  # a glass unit's weight: every ply and interlayer (ids P0001.k -> P0001)
        if g.kind == "panel":
            for i, m in zip(g.ids, g.volume_mm3 * spec.group_density(g) * 1e-9):
                unit_kg[i.split(".", 1)[0]] = unit_kg.get(i.split(".", 1)[0], 0.0) + float(m)
    found["weight"] = [(i, m) for i, m in unit_kg.items() if m > lim.max_panel_kg]
    for g in groups:
        cap = g.kind == "node" and cut_from_sheet(g.kind, g.member)   # a tube hub's top and bottom cap plates
        if (g.kind not in ("panel", "beam") and not cap) or getattr(g, "material", "") or not len(g):
            continue  # an interlayer is not cut from sheet; a hub tube is a section, a solid hub turned
        if cap:
            edge = min_widths(g.bevel_ref)
        else:
            L = edge_lengths(g.bevel_ref)
            if g.kind == "beam" and len(g.faces) == 6:  # a flange or box web: its end cuts are as long as it is wide
                L = L[:, [0, 2]]
            edge = L.min(axis=1)
        found["edge"] += [(i, float(e)) for i, e in zip(g.ids, edge) if e < lim.min_edge_mm]
        if g.kind == "beam":
            continue
        corner = corner_angles_deg(g.bevel_ref).min(axis=1)
        found["corner"] += [(i, float(c)) for i, c in zip(g.ids, corner) if c < lim.min_corner_deg]
        if cap:
            continue
        w, h = g.rect[:, 0], g.rect[:, 1]
        fits = ((w <= W) & (h <= H)) | ((w <= H) & (h <= W))
        found["sheet"] += [(i, f"{a:.0f} x {b:.0f}") for i, a, b, ok in zip(g.ids, w, h, fits) if not ok]
    limit = {"corner": f">= {lim.min_corner_deg:g} deg", "edge": f">= {lim.min_edge_mm:g} mm",
             "sheet": f"within {W:g} x {H:g} mm", "weight": f"<= {lim.max_panel_kg:g} kg"}
    out = {}
    for key in ("corner", "edge", "sheet"):  # a unit (glass unit, beam, hub) is flagged once, by its id, at its worst solid
        best: dict[str, tuple] = {}
        for pid, value in found[key]:
            uid = pid.split(".", 1)[0]
            if uid not in best or (key != "sheet" and value < best[uid][1]):
                best[uid] = (uid, value)
        found[key] = list(best.values())
    for key, rows in found.items():
        entry = {"limit": limit[key], "count": len(rows), "ids": [r[0] for r in rows]}
        if rows:
            worst = (max if key == "weight" else min)(rows, key=lambda r: r[1]) if key != "sheet" else rows[0]
            entry.update(worst=worst[1], worst_id=worst[0])
        out[key] = entry
    return out
