"""The totals a client asks first: glass area, steel length and weight, how many different parts.

``client_totals(parts)`` is JSON-ready (``report.json["totals"]``) and is
shown at the top of report.html and in the console summary of ``fabricate
run``.  Different parts are congruence classes within :data:`SIZE_TOL_MM`
(:mod:`fabricate.cad.congruence`): glass shapes (every ply's outline; a mirror
image is the same shape's other hand, which a glass order lists as a position
of its own because laminated and coated glass has a side), node types (beam
directions in the node's frame) and beam types (length, end cuts, ridge
bevels).  ``distinct_panel_sizes`` counts the glass order's positions (shapes
and their hands), ``glass_shapes`` the shapes with mirror images as one.
"""
from __future__ import annotations

import numpy as np

from fabricate.cad.congruence import TOLERANCE_MM

SIZE_TOL_MM = TOLERANCE_MM
"""Parts whose corners all match within this are one type (a glass cutter's mm)."""


def distinct_sizes(flat: np.ndarray, thickness: np.ndarray, tol: float = SIZE_TOL_MM) -> np.ndarray:
    """(p,) int size label of every outline ``flat (p, k, 2)`` (labels 0..s-1): congruent within ``tol``
    (:func:`fabricate.cad.congruence.ring_classes`), of equal thickness within ``tol``, mirror images apart."""
    from fabricate.cad.congruence import ring_classes

    flat = np.asarray(flat, dtype=float)
    p, k = flat.shape[:2]
    if p == 0:
        return np.zeros(0, dtype=np.int64)
    F = np.broadcast_to(np.asarray(thickness, dtype=float)[:, None, None, None], (p, 1, k, 1))
    c = ring_classes(flat[:, None], tol, F=F)
    _, labels = np.unique(np.stack([c.label, c.hand], axis=1), axis=0, return_inverse=True)
    return labels.ravel()


def repetition(parts, tol: float = SIZE_TOL_MM) -> dict:
    """How many different parts (JSON-ready, ``report.json["repetition"]``): per kind (``glass``,
    ``nodes``, ``beams``) the parts, their types (mirror images as one), the types with mirror images
    apart, the largest type, the largest deviation from a type's drawing (mm) and the tolerance."""
    from fabricate.export.schedules import beam_types, glass_types, node_types

    out = {"tolerance_mm": tol, "rule": "congruent within the tolerance at every corner (glass: every ply's "
           "outline; nodes: beam directions at the beam depth in the node axis frame; beams: length, end cuts "
           "and ridge bevels at the beam depth, either end first); mirror images are one type's two hands"}
    for key, fn in (("glass", glass_types), ("nodes", node_types), ("beams", beam_types)):
        out[key] = fn(parts, tol)[2].summary()
    return out


def client_totals(parts) -> dict | None:
    """Glass area (m2), panel count and distinct sizes; steel length (m) and weight (kg, t)."""
    if parts is None:
        return None
    from fabricate.cad.glass import bearing_groups
    from fabricate.cad.parts import unit_id

    panels = parts.of_kind("panel")
    units = bearing_groups(parts)          # one solid per glass unit: its ply on the beams
    area = sum(float(np.sum(g.area_mm2)) for g in units)  # a ply of the same face is not more glass area
    rep = repetition(parts)
    glass = rep["glass"]
    steel = [g for kind in ("beam", "node") for g in parts.of_kind(kind)]
    density = parts.spec.density("beam")
    steel_kg = sum(float(np.sum(g.volume_mm3)) for g in steel) * 1e-9 * density
    glass_kg = sum(float(np.sum(g.volume_mm3)) * parts.spec.group_density(g) for g in panels) * 1e-9
    from fabricate.export.schedules import beam_units

    length = sum(float(np.sum(g.length_mm)) for g in beam_units(parts))   # one length per beam, not per plate
    return {"glass_area_m2": area * 1e-6, "panels": sum(len(g) for g in units),
            "build_up": parts.spec.glass.short() if hasattr(parts.spec, "glass") else "",
            "distinct_panel_sizes": glass["with_hands"], "most_panels_of_one_size": glass["most_of_one_type"],
            "glass_shapes": glass["types"], "node_types": rep["nodes"]["types"],
            "nodes": rep["nodes"]["parts"], "beam_types": rep["beams"]["types"],
            "size_tolerance_mm": SIZE_TOL_MM,
            "size_rule": f"congruent within {SIZE_TOL_MM:g} mm at every corner of every ply; a size is a shape "
                         "and hand (a mirror image is another size, and the same shape)",
            "repetition": rep,
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
    shapes = t.get("glass_shapes")
    shapes = f"{shapes:,} shapes, mirror images as one; " if shapes is not None else ""
    beams = f"{t['beams']:,}" + (f" of {t['beam_types']:,} types" if t.get("beam_types") is not None else "")
    nodes = (f", {t['nodes']:,} nodes of {t['node_types']:,} types" if t.get("node_types") is not None
             and t.get("nodes") else "")
    return [f"glass{bu} {t['glass_area_m2']:,.1f} m2 in {t['panels']:,} panels of {t['distinct_panel_sizes']:,} "
            f"distinct sizes ({shapes}within {t['size_tolerance_mm']:g} mm; at most "
            f"{t['most_panels_of_one_size']:,} of one size), {kg(t['glass_mass_kg'])}",
            f"steel {t['steel_length_m']:,.1f} m of beams ({beams}{nodes}), {kg(t['steel_mass_kg'])} = "
            f"{t['steel_mass_t']:,.2f} t with the nodes"]
