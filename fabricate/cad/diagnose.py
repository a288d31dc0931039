"""Why a part cannot be built, said in the fabricator's terms.

A glass panel is its face inset by half the joint gap.  On a face that is
too narrow for that (a squeezed quad, a near-triangle, a quad near the
singular curve of a developable strip) the inset polygon turns inside out:
no glass can be cut.  :func:`panel_failure` names every such panel, how
narrow its face is, and the largest ``parts.joint_gap`` (and the other
``parts.edge`` option) with which it builds, so the message says what to
change: the gap, the edge option, or, when not even a zero gap works, the
design (see the design's own parameters and ``optimize.fairness``).  Panels far beyond any
building (coordinates so large that float64 cannot hold the CAD tolerance) are said to be that.
"""
from __future__ import annotations

import numpy as np

from optimize.mesh.measures import range_problem
from optimize.tolerances import DEFAULT

from .errors import PartError

from .geometry import convexity, dot

CONVEX_MIN = 1e-9
"""Smallest accepted ``sin`` of a face corner's turn (a fold or a collapsed edge below it)."""
BISECTIONS = 30


def min_turn(V: np.ndarray, faces, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Worst corner turn of every solid ``(p,)`` and the face where it is ``(p,)`` int.

    V : (p, nv, 3) vertices; faces : shared face tuples; normals : (p, nf, 3) outward.
    """
    turns = np.stack([convexity(V[:, list(face)], normals[:, fi]) for fi, face in enumerate(faces)], axis=1)
    return turns.min(axis=1), turns.argmin(axis=1)


def face_widths(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shortest edge ``(p,)`` and width ``(p,)`` (least distance between a side line and the
    farthest corner: the narrowest strip holding the polygon) of planar polygons ``P (p, k, 3)``."""
    E = np.roll(P, -1, axis=1) - P
    length = np.linalg.norm(E, axis=2)
    t = E / np.where(length > 0, length, 1.0)[..., None]
    D = P[:, None, :, :] - P[:, :, None, :]               # (p, edge j, corner i, 3) from corner j
    along = dot(D, t[:, :, None, :])
    dist = np.linalg.norm(D - along[..., None] * t[:, :, None, :], axis=3)
    return length.min(axis=1), dist.max(axis=2).min(axis=1)


def _builds(build, gap: float, faces: np.ndarray, mode: str) -> np.ndarray:
    """(q,) bool: which of the mesh faces ``faces`` give a valid panel with this gap and mode."""
    ok = np.zeros(len(faces), dtype=bool)
    for g in build(gap, mode, faces):
        turn, _ = min_turn(g["vertices"], g["faces"], g["normals"])
        ok[np.searchsorted(faces, g["faces_index"])] = turn >= CONVEX_MIN
    return ok


def largest_gap(build, gap: float, faces: np.ndarray, mode: str) -> float | None:
    """The largest joint gap ``<= gap`` (mm, to 0.1 mm below the exact bound) with which every panel of
    ``faces (q,)`` builds in ``mode``, or None when even no gap does not.  ``build(gap, mode, faces)``
    returns the batches of :func:`fabricate.cad.panels.panel_solids`."""
    faces = np.sort(np.asarray(faces))
    if not _builds(build, 0.0, faces, mode).all():
        return None
    lo, hi = 0.0, float(gap)
    for _ in range(BISECTIONS):  # bisection on one number; each step builds the failing panels only
        if hi - lo < 0.05:
            break
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if _builds(build, mid, faces, mode).all() else (lo, mid)
    return float(np.floor(lo * 10.0) / 10.0)


def panel_failure(ids, faces_index, face_name: str, turn: float, P: np.ndarray, normal: np.ndarray, spec,
                  mode: str, build) -> PartError:
    """The error for panels that fold.

    ids : (q,) str part ids of every failing panel, worst first; faces_index : (q,) their mesh faces;
    face_name, turn : where the worst one folds and its corner turn;
    P : (1, k, 3) the worst panel's face polygon at the glass layer (mm); normal : (3,) its unit normal;
    build : ``build(gap, mode, faces)`` as in :func:`largest_gap`.
    """
    listed = f"{', '.join(ids[:8])}{', ...' if len(ids) > 8 else ''}"
    far = range_problem(P, resolution=DEFAULT.cad_linear_mm, needs="the CAD tolerance")
    if far:  # the glass thickness and the joint gap are lost in rounding: no face is too narrow
        return PartError(f"panel {ids[0]} (face {int(faces_index[0])}): no part can be built, {far}; "
                         f"{len(ids)} panel(s) fail ({listed})", str(ids[0]), int(faces_index[0]))
    own = max(float(convexity(P, normal[None])[0]), float(convexity(P, -normal[None])[0]))  # either way round
    if not own >= CONVEX_MIN:  # the mesh face itself turns inside out: no setting of the parts helps
        return PartError(
            f"panel {ids[0]} (face {int(faces_index[0])}): the mesh face itself is folded (a self-intersecting "
            f"or non-convex polygon, corner turn {own:.3g}, expected > 0); {len(ids)} panel(s) fail ({listed}). "
            "No glass can be cut from it: the optimized mesh is not valid there (see mesh.obj and the "
            "optimizer's report); check the input and the optimize settings", str(ids[0]), int(faces_index[0]))
    shortest, width = face_widths(P)
    gap = spec.joint_gap
    other = "perpendicular" if mode == "axis" else "axis"
    fits = largest_gap(build, gap, faces_index, mode)
    other_ok = bool(_builds(build, gap, np.sort(np.asarray(faces_index)), other).all())
    head = (f"panel {ids[0]} (face {int(faces_index[0])}): the glass inset by parts.joint_gap / 2 = "
            f"{0.5 * gap:g} mm folds (face {face_name}, corner turn {turn:.3g}, expected > 0); the face is "
            f"too narrow for it: shortest edge {shortest[0]:.1f} mm, width {width[0]:.1f} mm")
    more = f"; {len(ids)} panels fail ({listed})" if len(ids) > 1 else ""
    they, build_s, do = ("it", "builds", "does") if len(ids) == 1 else ("they", "build", "do")
    if fits is not None and fits > 0:
        fix = f"{they} {build_s} with parts.joint_gap <= {fits:g} mm"
    elif fits == 0:
        fix = f"{they} {build_s} only without a joint gap"
    else:
        fix = f"{they} {do} not build even without a joint gap (the face is degenerate)"
    if other_ok:
        fix += f", or with parts.edge: {other}"
    return PartError(f"{head}{more}; {fix}. Faces this narrow come from the design (a squeezed quad, or a "
                       "developable strip whose singular curve comes near the strip): a design that keeps its "
                     "quads regular (design parameters, optimize.fairness) avoids them", str(ids[0]),
                     int(faces_index[0]))


def beam_hint(planarity_mm: float, width: float, shrink: float = 1.0, depth: float = 0.0, *,
              length_mm: float | None = None, setback_mm: float = 0.0, connection: str = "hub") -> str:
    """What to change for a beam that folds, given how far its quad is off its plate's mid-plane,
    ``shrink`` (its edge at the last layer over its edge at the first, negative when reversed),
    ``depth`` (mm, first to last layer), its edge ``length_mm`` at the glass, how far its square ends
    stand off the node axes (``setback_mm``, :attr:`fabricate.cad.PartSpec.end_setback`) and the node
    ``connection`` (advice never names what is already set)."""
    if shrink < 0.25 and depth > 0:  # the node axes of its ends meet within the beam's depth
        zero = depth / (1.0 - shrink) if shrink < 1.0 else depth
        what = "reversed" if shrink < 0 else f"{shrink:.0%} of its length"
        return (f"the node axes of its two ends meet about {zero:.0f} mm from the glass, within the beam depth "
                f"of {depth:g} mm (its edge at the last layer is {what}): the beams are deeper than the "
                "surface's curvature allows there; reduce parts.beam_depth (or the last of offset.distances)")
    if planarity_mm > 0.25 * width:
        return (f"its quad twists: corners up to {planarity_mm:.1f} mm off the plate's mid-plane (beam width "
                f"{width:g} mm), the mesh is not conical there; optimize.target: conical makes the beams "
                "planar, or use a wider parts.beam_width (parts.beam.web_mm for a section)")
    size = f" (its edge is {length_mm:.0f} mm long" if length_mm is not None else ""
    if size and setback_mm > 0:
        size += f", its square ends stand {setback_mm:g} mm off each node axis"
    size += ")" if size else ""
    if connection == "mitre":  # mitred in the bisector planes: the end planes cross within the beam
        return (f"its mitred ends cross within the beam{size}: a neighbouring beam meets it at a sharp angle; "
                "reduce parts.beam_width (a section: parts.beam.flange_width_mm), or use hubs "
                "(parts.node.connection: hub) with a radius that clears the sharpest angle")
    fixes = ["reduce parts.beam_width (a section: parts.beam.flange_width_mm)"]
    if connection == "hub":
        fixes.append("the hub (parts.node.radius_mm, parts.node_radius)"
                     + (f" to below {0.45 * length_mm:.0f} mm" if length_mm is not None else ""))
    elif connection == "none":
        fixes.append("the gap at the nodes (parts.node.gap_mm)")
    return (f"the beam may be shorter than its end trims{size}: " + " or ".join(fixes)
            + ", or use parts.node.connection: mitre")
