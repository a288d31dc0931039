"""The totals a client asks first: glass area, steel length and weight, distinct panel sizes.

``client_totals(parts)`` is JSON-ready (``report.json["totals"]``) and is
shown at the top of report.html and in the console summary of ``fabricate
run``.  Panel sizes: two panels are the same size when their flat outlines
(:attr:`PartGroup.flat`, mm) are congruent within ``SIZE_TOL_MM`` (every
corner-to-corner distance, for some cyclic relabelling of the corners;
mirror images count as different sizes because laminated and coated glass
has a side) and their thicknesses agree within the same tolerance.  Groups
are the connected components of "congruent within the tolerance", so a chain
of panels each within 1 mm of the next is one size.
"""
from __future__ import annotations

import numpy as np

SIZE_TOL_MM = 1.0
"""Outlines whose corner distances all agree within this are one panel size (a glass cutter's mm)."""


def _signatures(flat: np.ndarray, shift: int) -> np.ndarray:
    """(p, k*k) corner-to-corner distances of the outlines ``flat (p, k, 2)`` relabelled by ``shift``,
    with the signed double areas of the corner triangles (so a mirror image differs)."""
    P = np.roll(flat, -shift, axis=1)
    D = np.linalg.norm(P[:, :, None, :] - P[:, None, :, :], axis=3)
    Q = np.roll(P, -1, axis=1) - P
    R = np.roll(P, -2, axis=1) - P
    turn = Q[..., 0] * R[..., 1] - Q[..., 1] * R[..., 0]          # (p, k): signed, mm^2
    scale = np.maximum(np.linalg.norm(Q, axis=2), 1e-300)
    return np.concatenate([D.reshape(len(P), -1), turn / scale], axis=1)


def distinct_sizes(flat: np.ndarray, thickness: np.ndarray, tol: float = SIZE_TOL_MM) -> np.ndarray:
    """(p,) int size label of every outline ``flat (p, k, 2)`` (labels 0..s-1)."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    p, k = flat.shape[:2]
    if p == 0:
        return np.zeros(0, dtype=np.int64)
    base = np.concatenate([_signatures(flat, 0), thickness[:, None]], axis=1)
    tree = cKDTree(base)
    rows, cols = [np.arange(p)], [np.arange(p)]
    for s in range(k):  # every relabelling of the corners against the unshifted ones
        S = np.concatenate([_signatures(flat, s), thickness[:, None]], axis=1)
        pairs = cKDTree(S).query_ball_tree(tree, r=tol, p=np.inf)
        cnt = np.fromiter((len(x) for x in pairs), dtype=np.int64, count=p)
        rows.append(np.repeat(np.arange(p), cnt))
        cols.append(np.fromiter((j for x in pairs for j in x), dtype=np.int64, count=int(cnt.sum())))
    r, c = np.concatenate(rows), np.concatenate(cols)
    G = sp.coo_matrix((np.ones(len(r)), (r, c)), shape=(p, p))
    _, labels = connected_components(G, directed=False)
    return labels


def client_totals(parts) -> dict | None:
    """Glass area (m2), panel count and distinct sizes; steel length (m) and weight (kg, t)."""
    if parts is None:
        return None
    from fabricate.cad.glass import bearing_groups
    from fabricate.cad.parts import unit_id

    panels = parts.of_kind("panel")
    area = 0.0
    sizes = 0
    largest = 0
    units = bearing_groups(parts)          # one solid per glass unit: its ply on the beams
    for g in units:  # one area per panel position (a ply of the same face is not more glass area)
        area += float(np.sum(g.area_mm2))
        labels = distinct_sizes(np.asarray(g.flat, dtype=float), np.asarray(g.thickness_mm, dtype=float))
        if labels.size:
            sizes += int(labels.max()) + 1
            largest = max(largest, int(np.bincount(labels).max()))
    steel = [g for kind in ("beam", "node") for g in parts.of_kind(kind)]
    density = parts.spec.density("beam")
    steel_kg = sum(float(np.sum(g.volume_mm3)) for g in steel) * 1e-9 * density
    glass_kg = sum(float(np.sum(g.volume_mm3)) * parts.spec.group_density(g) for g in panels) * 1e-9
    from fabricate.export.schedules import beam_units

    length = sum(float(np.sum(g.length_mm)) for g in beam_units(parts))   # one length per beam, not per plate
    return {"glass_area_m2": area * 1e-6, "panels": sum(len(g) for g in units),
            "build_up": parts.spec.glass.short() if hasattr(parts.spec, "glass") else "",
            "distinct_panel_sizes": sizes, "most_panels_of_one_size": largest,
            "size_tolerance_mm": SIZE_TOL_MM,
            "size_rule": "congruent flat outlines (corner distances, mirror images differ) and equal "
                         f"thickness, within {SIZE_TOL_MM:g} mm",
            "glass_mass_kg": glass_kg, "beams": len({unit_id(i) for g in parts.of_kind("beam") for i in g.ids}),
            "steel_length_m": length * 1e-3, "steel_mass_kg": steel_kg, "steel_mass_t": steel_kg * 1e-3,
            "steel_includes": "beams and nodes"}


def kg(x: float) -> str:
    """A mass for people: ``2,640 kg``, ``12.5 kg``, ``0.42 kg``."""
    if x >= 100:
        return f"{x:,.0f} kg"
    return f"{x:.3g} kg"


def totals_lines(t: dict | None) -> list[str]:
    """The totals as short lines (console summary, the report's summary table)."""
    if not t:
        return []
    bu = f" {t['build_up']} mm" if t.get("build_up") else ""
    return [f"glass{bu} {t['glass_area_m2']:,.1f} m2 in {t['panels']:,} panels of {t['distinct_panel_sizes']:,} "
            f"distinct sizes (within {t['size_tolerance_mm']:g} mm; at most {t['most_panels_of_one_size']:,} "
            f"of one size), {kg(t['glass_mass_kg'])}",
            f"steel {t['steel_length_m']:,.1f} m of beams ({t['beams']:,}), {kg(t['steel_mass_kg'])} = "
            f"{t['steel_mass_t']:,.2f} t with the nodes"]
