"""Hub size from the sharpest beam angle: the smallest stock tube on which no two beams clash.

Seen along a node axis, every beam is a strip of half-width ``h`` (half the wider of its web and
its flanges) leaving the axis at its azimuth; its square end stands ``r`` (the hub radius) off
the axis.  Two neighbouring beams ``theta`` apart clear each other when
``r >= (h + clearance) / tan(theta / 2)``; the projection along the axis is conservative (the
beams span the same depth, so strips that overlap there clash in space).  The hub radius is the
smallest stock circular hollow section (EN 10219 / EN 10210 outside diameters) that clears the
sharpest pair at every node, at least the tube's wall plus ``clearance``.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from optimize.errors import ConfigError

STOCK_CHS_MM = (60.3, 76.1, 88.9, 101.6, 114.3, 139.7, 168.3, 193.7, 219.1, 244.5, 273.0, 323.9, 355.6,
                406.4, 457.0, 508.0)
"""Outside diameters (mm) of circular hollow sections stocked in the EN 10219 / EN 10210 ranges."""

CLEARANCE_MM = 5.0
"""Gap kept between two beam ends at the hub (mm): room for the welds and the fit-up."""


def sharpest_gaps(structure, P0: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(n,) float: at each node the smallest angle (rad) between two neighbouring beams seen along
    its axis (:func:`fabricate.cad.beams.angular_neighbours`, which sets the square ends back by the
    same rule); ``2 pi`` at a node with fewer than two beams.

    structure : :class:`fabricate.offset.OffsetStructure`; P0 : (n, 3) the vertices at the first
    layer; normal : (e, 3) the oriented beam normals (``beam_planes(structure)["normal"]``).
    """
    from .beams import angular_neighbours

    gap = angular_neighbours(structure, P0, normal)["gap"].min(axis=2)    # (e, 2): per beam end
    out = np.full(len(P0), 2 * np.pi)
    np.minimum.at(out, np.asarray(structure.edges).ravel(), gap.ravel())
    return out


def needed_radius(gaps: np.ndarray, half_width: float, clearance: float = CLEARANCE_MM) -> np.ndarray:
    """(n,) mm: the hub radius at which two beams of half-width ``half_width`` (mm), ``gaps (n,)``
    rad apart, clear each other by ``clearance``; 0 where the gap is 180 deg or more."""
    half = 0.5 * np.minimum(np.asarray(gaps, dtype=float), np.pi)
    with np.errstate(divide="ignore"):
        return np.where(half > 0, (half_width + clearance) / np.tan(half), np.inf)


def size_hubs(structure, spec, P0: np.ndarray, normal: np.ndarray):
    """``(spec, facts)``: ``spec`` with ``node.radius_mm`` sized here when the connection is a hub and
    no radius is given (``parts.node.radius_mm: null``, ``parts.node_radius: 0``), and what the
    sizing found (``facts``: the sharpest node, its angle, the radius it needs; None without hubs).

    Raises :class:`fabricate.cad.PartError` (the node, its angle and what would work) when no stock
    tube is large enough.  A radius given in the config is kept; below what a node needs, the shop
    limit ``hub`` lists the nodes (:func:`hub_limit`).
    """
    if spec.connection != "hub":
        return spec, None
    from .errors import PartError
    from .parts import part_ids

    half = 0.5 * max(spec.web, spec.bearing_width)
    gaps = sharpest_gaps(structure, P0, normal)
    need = needed_radius(gaps, half)
    worst = int(np.argmax(need))
    nid = part_ids("node", np.array([worst, len(need) - 1]))[0]
    facts = {"sharpest_node": nid, "sharpest_deg": float(np.degrees(gaps[worst])),
             "needed_radius_mm": float(need[worst]), "half_width_mm": half, "clearance_mm": CLEARANCE_MM,
             "sized": spec.node.radius_mm is None and spec.node_radius <= 0}
    if not facts["sized"]:
        return spec, facts
    floor = max(float(need.max()), spec.node.wall_mm + CLEARANCE_MM if spec.hub_kind == "tube" else 0.0)
    fits = [0.5 * D for D in STOCK_CHS_MM if 0.5 * D >= floor]
    if not fits:
        raise PartError(
            f"node {nid}: two of its beams are {facts['sharpest_deg']:.1f} deg apart seen along its axis, so "
            f"{2 * half:g} mm wide beams need a hub of radius {need[worst]:.0f} mm to clear each other, more "
            f"than the largest stock tube (D {STOCK_CHS_MM[-1]:g} mm); use parts.node.connection: mitre, "
            "narrower beams (parts.beam_width, parts.beam.flange_width_mm), or a design without such sharp "
            "angles between beams", nid, worst)
    node = dataclasses.replace(spec.node, radius_mm=fits[0])
    facts["radius_mm"] = fits[0]
    try:
        return dataclasses.replace(spec, node=node), facts
    except ConfigError as exc:  # the sized tube and the rest of the settings disagree (wall, caps)
        raise PartError(f"node {nid}: the hub sized to D {2 * fits[0]:g} mm for the sharpest beam angle "
                        f"({facts['sharpest_deg']:.1f} deg) does not fit the other settings: {exc}", nid,
                        worst) from exc


def hub_limit(structure, spec, facts, P0: np.ndarray, normal: np.ndarray) -> dict | None:
    """The shop limit ``hub`` (as :func:`fabricate.cad.limits.check_limits` gives its limits): the nodes
    where a hub radius given in the config is below what the sharpest beam angle needs (their beams
    clash); None without hubs."""
    if facts is None:
        return None
    from .parts import part_ids

    need = needed_radius(sharpest_gaps(structure, P0, normal), facts["half_width_mm"])
    short = np.nonzero(need > spec.hub_radius + 1e-9)[0]
    ids = list(part_ids("node", np.r_[short, len(need) - 1])[:-1]) if len(short) else []
    top = float(need.max())
    entry = {"limit": f"beam ends on the hub: radius {spec.hub_radius:g} mm, the beam angles need up to "
                      f"{np.ceil(top):.0f} mm (parts.node.radius_mm: null sizes it; below it the ends stand off)",
             "count": len(ids), "ids": ids}
    if len(short):
        worst = short[np.argmax(need[short])]
        entry.update(worst=float(need[worst]), worst_id=part_ids("node", np.array([worst, len(need) - 1]))[0])
    return entry
