"""The glass order's delivery: install sequence, zones and racks along the layout plan (issue 36).

The units go in along the roof's long plan axis (the first principal axis of the
unit centres in plan): *rows* across that axis, one median unit wide, taken in
order along it, each row snaking back and forth so the crane never jumps.  A *zone*
is a strip of the plan across the long axis, ``zone_mm`` long (:data:`ZONE_MM`),
holding the rows that start in it: a delivery is called off zone by zone.  Racks are
filled in install order and never span two zones: a new rack when the zone changes,
when the rack holds ``rack_units`` units (:data:`RACK_UNITS`) or when the next unit
would take it over ``rack_kg`` of glass (:data:`RACK_KG`).  A unit heavier than
``rack_kg`` alone goes on a rack of its own, marked over the limit.  Slot 1 of a rack
is its front: the first unit of the rack to go in.

:func:`sequence` is pure (arrays in, arrays out); :func:`rack_rows` gives the rows of
``glass_order/racks.csv`` (:data:`RACK_COLUMNS`).
"""
from __future__ import annotations

import numpy as np

RACK_UNITS = 20
"""Most units on one delivery rack (an A-frame or L-rack; one A4 sheet of labels holds them)."""
RACK_KG = 1500.0
"""Most glass on one delivery rack (kg): a site crane's and a standard A-frame's usual load."""
ZONE_MM = 10000.0
"""Length of a delivery zone along the roof's long plan axis (mm)."""
RACK_COLUMNS = ("rack", "zone", "install_from", "install_to", "units", "unit_ids", "positions", "weight_kg",
                "max_weight_kg", "over_limit", "largest_blank_mm", "label_sheet")


def sequence(centre: np.ndarray, weight: np.ndarray, size_mm: float, rack_kg: float = RACK_KG,
             rack_units: int = RACK_UNITS, zone_mm: float = ZONE_MM) -> dict:
    """Install order, zones and racks of ``u`` units.

    centre : (u, 3) unit centres in the model (mm, z up); weight : (u,) kg; size_mm : the row width
    (a median unit's side).  Returns ``seq (u,)`` 1-based install order, ``row (u,)``, ``zone (u,)``
    1-based, ``rack (u,)`` 1-based in install order, ``slot (u,)`` 1-based place on the rack (1 =
    front, first in), ``rack_kg`` the limit used.  Raises ValueError for a limit that is not positive.
    """
    if not rack_kg > 0 or not zone_mm > 0 or int(rack_units) < 1:
        raise ValueError(f"rack_kg {rack_kg}, rack_units {rack_units}, zone_mm {zone_mm}: expected positive")
    centre = np.asarray(centre, dtype=float).reshape(-1, 3)
    weight = np.asarray(weight, dtype=float).reshape(-1)
    n = len(centre)
    if n == 0:
        z = np.zeros(0, dtype=np.int64)
        return {"seq": z, "row": z, "zone": z, "rack": z, "slot": z, "rack_kg": float(rack_kg)}
    xy = centre[:, :2] - centre[:, :2].mean(axis=0)
    axes = np.linalg.svd(xy, full_matrices=False)[2] if n > 1 else np.eye(2)
    u, v = xy @ axes[0], xy @ axes[1]
    u0 = u.min()
    size = max(float(size_mm), 1.0)
    row = np.floor((u - u0) / size + 0.5).astype(np.int64)                # rows centred on the first
    order = np.lexsort((np.where(row % 2 == 0, v, -v), row))             # snake along each row
    seq = np.empty(n, dtype=np.int64)
    seq[order] = np.arange(1, n + 1)
    zone_of_row = np.floor(np.arange(row.max() + 1) * size / float(zone_mm)).astype(np.int64)
    used = np.unique(zone_of_row[row])
    zone = np.searchsorted(used, zone_of_row[row]) + 1                   # zones numbered 1.. as used
    rack = np.zeros(n, dtype=np.int64)
    slot = np.zeros(n, dtype=np.int64)
    r, count, kg, current = 0, 0, 0.0, -1
    for i in order.tolist():  # racks filled in install order (bookkeeping per unit)
        if count == 0 or zone[i] != current or count >= rack_units or kg + weight[i] > rack_kg:
            r, count, kg, current = r + 1, 0, 0.0, int(zone[i])
        count += 1
        kg += weight[i]
        rack[i], slot[i] = r, count
    return {"seq": seq, "row": row + 1, "zone": zone, "rack": rack, "slot": slot, "rack_kg": float(rack_kg)}


def rack_name(r: int) -> str:
    """``R001`` for rack 1."""
    return f"R{int(r):03d}"


def rack_rows(seq: dict, ids, names, weight: np.ndarray, blank: np.ndarray, sheets: dict[int, str]) -> list[tuple]:
    """The rows of ``racks.csv`` (:data:`RACK_COLUMNS`), one per rack in install order.

    seq : :func:`sequence`'s dict; ids, names : (u,) unit ids and their positions; weight : (u,) kg;
    blank : (u, 2) mm; sheets : rack -> the label sheet(s) of its units."""
    out = []
    order = np.argsort(seq["seq"])
    for r in np.unique(seq["rack"]).tolist():  # one row per rack
        m = order[seq["rack"][order] == r]                                # its units, front first
        kg = float(weight[m].sum())
        b = blank[m]
        big = b[np.argmax(b[:, 0] * b[:, 1])]
        out.append((rack_name(r), int(seq["zone"][m[0]]), int(seq["seq"][m[0]]), int(seq["seq"][m[-1]]), len(m),
                    " ".join(ids[i] for i in m.tolist()), " ".join(dict.fromkeys(names[i] for i in m.tolist())),
                    f"{kg:.1f}", f"{seq['rack_kg']:g}", "yes" if kg > seq["rack_kg"] else "",
                    f"{big[0]:.0f} x {big[1]:.0f}", sheets.get(r, "")))
    return out
