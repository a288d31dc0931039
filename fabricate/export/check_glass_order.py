"""Hold the written glass order to the solids: ``glass_order.csv`` and its DXF drawings read back.

:func:`check_glass_order` finds, from the files alone and the parts' flat data:

- every glass unit in exactly one position (none missing, none twice, no unknown id);
- every position's drawing (``glass_order/<position>.dxf``: the cut outline of each ply on
  ``OUTLINE`` / ``PLY<k>``, the bearing lines on ``BEARING``) within the position's tolerance of
  each unit it covers, by a rigid motion without reflection (a mirror image is another position);
- every ply blank (``ply<k>_blank_w_mm`` x ``_h_mm``) and the unit blank holding that ply of every
  unit of the position (``PartGroup.rect``, either way round).

The result is one dict in the form of the other file checks: ``{"pass", "positions", "units",
"problems": [...], "largest_deviation_mm"}``; a problem names the file, the position and the unit.
"""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

ROUND_MM = 0.05
"""Allowance for the CSV's 0.1 mm figures."""


def _read_dxf_rings(path: Path) -> np.ndarray:
    """(2 n, k, 2) the rings of a position drawing: per ply its cut outline, then its bearing line."""
    import ezdxf

    doc = ezdxf.readfile(str(path))
    outlines: dict[int, np.ndarray] = {}
    bearing = []
    for e in doc.modelspace().query("POLYLINE"):  # a few polylines per drawing
        P = np.array([(v.dxf.location[0], v.dxf.location[1]) for v in e.vertices], dtype=float)
        layer = e.dxf.layer.upper()
        if layer == "OUTLINE":
            outlines[1] = P
        elif layer.startswith("PLY") and layer[3:].isdigit():
            outlines[int(layer[3:])] = P
        elif layer == "BEARING":
            bearing.append(P)
    if 1 not in outlines or len(bearing) != len(outlines):
        raise ValueError(f"{path}: expected an OUTLINE polyline and one BEARING line per ply, found "
                         f"{sorted(outlines)} outlines and {len(bearing)} bearing lines")
    rings = []
    for j, k in enumerate(sorted(outlines)):
        rings += [outlines[k], bearing[j]]
    if len({len(r) for r in rings}) != 1:
        raise ValueError(f"{path}: the plies' rings have different corner counts {[len(r) for r in rings]}")
    return np.stack(rings)


def check_glass_order(parts, folder) -> dict:
    """Check ``folder/glass_order.csv`` and ``folder/glass_order/*.dxf`` against ``parts`` (see the
    module text).  Never raises for a bad file: a file that cannot be read is a problem named in the
    result (``pass`` False)."""
    from fabricate.cad.congruence import glass_unit_rings, ring_deviation
    from fabricate.export.glass_order import FOLDER, _ply_blanks

    folder = Path(folder)
    path = folder / "glass_order.csv"
    problems: list[str] = []
    ids, element, subsets = glass_unit_rings(parts)
    rings = {}
    for index, X in subsets:  # a few corner counts
        for j, i in enumerate(index.tolist()):
            rings[ids[i]] = X[j]
    blanks = dict(zip(ids, _ply_blanks(parts, element)))
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        return {"pass": False, "positions": 0, "units": len(ids), "problems": [f"{path}: cannot read ({exc})"],
                "largest_deviation_mm": None}
    seen: dict[str, str] = {}
    worst = 0.0
    for line, row in enumerate(rows, start=2):  # one row per position
        name = row.get("position", "")
        units = (row.get("units") or "").split()
        try:
            tol = float(row["shape_tolerance_mm"])
            quantity = int(row["quantity"])
        except (KeyError, TypeError, ValueError) as exc:
            problems.append(f"{path}:{line}: position {name!r}: unreadable quantity or tolerance ({exc})")
            continue
        if quantity != len(units):
            problems.append(f"{path}:{line}: position {name}: quantity {quantity} but {len(units)} unit ids")
        for u in units:
            if u in seen:
                problems.append(f"{path}:{line}: unit {u} in positions {seen[u]} and {name}")
            elif u not in rings:
                problems.append(f"{path}:{line}: unit {u} of position {name} is no glass unit of the model")
            seen.setdefault(u, name)
        known = [u for u in units if u in rings]
        if not known:
            continue
        drawing = folder / FOLDER / f"{name}.dxf"
        try:
            D = _read_dxf_rings(drawing)
        except Exception as exc:  # any unreadable drawing is a finding, not a crash
            problems.append(f"{drawing}: cannot read the drawing of position {name} ({exc})")
            continue
        Y = [rings[u] for u in known]
        if any(y.shape != D.shape for y in Y):
            problems.append(f"{drawing}: {D.shape[0] // 2} plies of {D.shape[1]} corners, the units "
                            f"{' '.join(known)} have {Y[0].shape[0] // 2} of {Y[0].shape[1]}")
            continue
        dev, _ = ring_deviation(D, np.stack(Y))
        worst = max(worst, float(dev.max()))
        for u, d in zip(known, dev.tolist()):
            if d > tol + 1e-6:
                problems.append(f"{drawing}: unit {u} is {d:.2f} mm from the drawing of position {name} "
                                f"(tolerance {tol:g} mm)")
        n_plies = int(row.get("plies") or 0)
        for k in range(1, n_plies + 1):  # a few plies
            try:
                bw, bh = float(row[f"ply{k}_blank_w_mm"]), float(row[f"ply{k}_blank_h_mm"])
            except (KeyError, TypeError, ValueError):
                problems.append(f"{path}:{line}: position {name}: no blank for ply {k}")
                continue
            for u in known:
                w, h = blanks[u][k - 1]
                fits = (w <= bw + ROUND_MM and h <= bh + ROUND_MM) or (w <= bh + ROUND_MM and h <= bw + ROUND_MM)
                if not fits:
                    problems.append(f"{path}:{line}: position {name} ply {k}: blank {bw:.1f} x {bh:.1f} mm does "
                                    f"not hold unit {u}'s ply ({w:.1f} x {h:.1f} mm)")
    missing = [u for u in ids if u not in seen]
    if missing:
        problems.append(f"{path}: {len(missing)} glass unit(s) in no position: {' '.join(missing[:12])}"
                        + (" ..." if len(missing) > 12 else ""))
    return {"pass": not problems, "positions": len(rows), "units": len(ids), "problems": problems,
            "largest_deviation_mm": worst}
