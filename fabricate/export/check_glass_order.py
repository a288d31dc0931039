"""Hold the written glass order to the solids: ``glass_order.csv`` and its DXF drawings read back.

:func:`check_order` finds, from the files and the units' flat data:

- every glass unit in exactly one position (none missing, none twice, no unknown id);
- every position's drawing (``glass_order/<position>.dxf``: the cut outline of each ply on
  ``OUTLINE`` / ``PLY<k>``, the bearing lines on ``BEARING``) within the position's tolerance of
  each unit it covers, by a rigid motion without reflection (a mirror image is another position);
- every ply blank (``ply<k>_blank_w_mm`` x ``_h_mm``) holding that ply of every unit of the
  position, and the unit blank (``blank_w_mm`` x ``_h_mm``) every ply (``PartGroup.rect``, either way
  round); the row's ``plies`` the units' count;
- the delivery (:func:`check_delivery`): every unit once in ``labels.csv``, ``racks.csv`` and the
  label sheets, every rack within its weight limit.

The result is one dict in the form of the other file checks: ``{"pass", "positions", "units",
"problems": [...], "largest_deviation_mm", "against"}`` (and ``why``, the first problems, when it
fails); a problem names the file, the position and the unit.

The units and their plies come from the parts in memory (:func:`check_glass_order`, the check
inside a run) or from the run's ``flat.json`` alone (:func:`check_glass_order_files`, the row
``glass_order`` of ``fabricate check``: the flat data the ``flat`` check holds to the STEP or 3MF
solids); one check, :func:`check_order`, takes either reference.
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

    from .verify import not_regular

    if (what := not_regular(path)) is not None:  # a pipe would block the open: refused unopened
        raise OSError(f"{path}: {what}, not a file")
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


def unit_reference(parts) -> dict:
    """The reference the order is held to, from the parts in memory: ``ids`` (u,) unit ids, ``rings``
    ``{id: (2 n, k, 2)}`` per glass ply outside in its cut outline and bearing line in the frame of the
    ply on the beams (:func:`fabricate.cad.congruence.glass_unit_rings`), ``blanks`` ``{id: (n, 2)}``
    each ply's ``PartGroup.rect``, ``against`` what they were read from."""
    from fabricate.cad.congruence import glass_unit_rings
    from fabricate.export.glass_order import _ply_blanks

    ids, element, subsets = glass_unit_rings(parts)
    rings = {}
    for index, X in subsets:  # a few corner counts
        for j, i in enumerate(index.tolist()):
            rings[ids[i]] = X[j]
    return {"ids": list(ids), "rings": rings, "blanks": dict(zip(ids, _ply_blanks(parts, element))),
            "against": "the parts", "problems": []}


def flat_reference(path) -> dict:
    """:func:`unit_reference` from a run's ``flat.json`` alone (what the ``flat`` check holds to the
    STEP or 3MF solids): every glass ply (``material`` glass, kind panel) of a unit, outside in by the
    number after its id's dot (``P0001.1`` the outer ply; a one-solid unit is its own ply), its
    ``outline`` and ``bevel_reference`` moved by its ``transform`` into the model and by the inverse
    of the bearing ply's (the unit's last glass ply) into that ply's frame; ``rect_mm`` its blank.
    A unit whose plies differ in corner count is a problem named in ``problems``.  Raises
    :class:`ExportError` for a flat.json that does not read."""
    from fabricate.cad.parts import unit_id
    from fabricate.export.flatdata import read_flat

    plies: dict[str, list[tuple[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]] = {}
    for g in read_flat(path):  # a few groups
        if g["kind"] != "panel" or g["material"] != "glass":
            continue
        for j, pid in enumerate(g["ids"]):  # bookkeeping per ply
            tail = pid.split(".", 1)[1] if "." in pid else "0"
            rank = int(tail) if tail.isdigit() else 0
            plies.setdefault(unit_id(pid), []).append((rank, g["outline"][j], g["bevel_reference"][j],
                                                       g["transform"][j], g["rect_mm"][j]))
    rings, blanks, problems = {}, {}, []
    for uid, own in plies.items():  # one unit each (a few plies)
        own.sort(key=lambda t: t[0])
        if len({len(t[1]) for t in own}) != 1:
            problems.append(f"{path}: unit {uid}: its plies have {[len(t[1]) for t in own]} corners in flat.json")
            continue
        to_bearing = np.linalg.inv(own[-1][3])
        out = []
        for _, outline, bearing, T, _ in own:  # a few plies
            for P in (outline, bearing):
                H = np.concatenate([P, np.zeros((len(P), 1)), np.ones((len(P), 1))], axis=1)
                out.append((H @ (to_bearing @ T).T)[:, :2])
        rings[uid] = np.stack(out)
        blanks[uid] = np.stack([t[4] for t in own])
    return {"ids": sorted(plies), "rings": rings, "blanks": blanks, "against": Path(path).name,
            "problems": problems}


def check_glass_order(parts, folder) -> dict:
    """Check ``folder/glass_order.csv`` and ``folder/glass_order/*.dxf`` against ``parts`` (see the
    module text).  Never raises for a bad file: a file that cannot be read is a problem named in the
    result (``pass`` False)."""
    return check_order(folder, unit_reference(parts))


def check_glass_order_files(folder, flat=None) -> dict:
    """The same check from a run folder's files alone: the reference from ``flat`` (default
    ``folder/flat.json``, :func:`flat_reference`); ``pass`` None (skipped) without it."""
    from optimize.errors import ExportError

    flat = Path(folder) / "flat.json" if flat is None else Path(flat)
    if not flat.is_file():
        return {"pass": None, "skipped": f"needs {flat.name}: the units' flat data the order is held to"}
    try:
        ref = flat_reference(flat)
    except ExportError as exc:
        return {"pass": False, "error": str(exc), "problems": [str(exc)], "why": [str(exc)]}
    return check_order(folder, ref)


def check_order(folder, ref: dict) -> dict:
    """Check ``folder/glass_order.csv`` and its drawings against ``ref`` (:func:`unit_reference` or
    :func:`flat_reference`); the result as in the module text, with ``against`` and, when it fails,
    ``why`` (the first problems)."""
    from fabricate.cad.congruence import ring_deviation
    from fabricate.export.glass_order import FOLDER

    folder = Path(folder)
    path = folder / "glass_order.csv"
    problems: list[str] = list(ref["problems"])
    ids, rings, blanks = ref["ids"], ref["rings"], ref["blanks"]
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        problems.append(f"{path}: cannot read ({exc})")
        return _result(problems, 0, len(ids), None, ref)
    seen: dict[str, str] = {}
    valid = set(ids)
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
            elif u not in valid:
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
        n_plies = len(blanks[known[0]])
        if (row.get("plies") or "").strip() != str(n_plies):
            problems.append(f"{path}:{line}: position {name}: plies {row.get('plies')!r}, its units have {n_plies}")
        for k in range(n_plies + 1):  # a few plies, then the unit's blank (k = 0) that holds every ply
            key = f"ply{k}_blank" if k else "blank"
            try:
                bw, bh = float(row[f"{key}_w_mm"]), float(row[f"{key}_h_mm"])
            except (KeyError, TypeError, ValueError):
                problems.append(f"{path}:{line}: position {name}: no {key}_w_mm / _h_mm")
                continue
            for u in known:
                for j in ([k - 1] if k else range(n_plies)):  # the ply, or every ply for the unit's blank
                    w, h = blanks[u][j]
                    if not ((w <= bw + ROUND_MM and h <= bh + ROUND_MM) or (w <= bh + ROUND_MM and h <= bw + ROUND_MM)):
                        what = f"ply {k}: blank" if k else "unit blank"
                        problems.append(f"{path}:{line}: position {name} {what} {bw:.1f} x {bh:.1f} mm does not "
                                        f"hold unit {u}'s ply {j + 1} ({w:.1f} x {h:.1f} mm)")
    missing = [u for u in ids if u not in seen]
    if missing:
        problems.append(f"{path}: {len(missing)} glass unit(s) in no position: {' '.join(missing[:12])}"
                        + (" ..." if len(missing) > 12 else ""))
    problems += check_delivery(folder / FOLDER, ids)
    return _result(problems, len(rows), len(ids), worst, ref)


def check_delivery(folder: Path, ids: list[str]) -> list[str]:
    """The problems of the delivery files in ``folder`` (``glass_order/``) for the units ``ids``: each
    unit once in ``labels.csv``, once in ``racks.csv`` (on the rack its label names), and its label once
    in its rack's label sheets; every rack's weight the sum of its units' and within its
    ``max_weight_kg`` (but a single unit over the limit, marked ``over_limit``)."""
    import re
    from collections import Counter

    problems: list[str] = []
    tables = {}
    for name in ("labels.csv", "racks.csv"):  # two tables
        try:
            with open(folder / name, newline="", encoding="utf-8") as fh:
                tables[name] = list(csv.DictReader(fh))
        except (OSError, UnicodeDecodeError, csv.Error) as exc:
            problems.append(f"{folder / name}: cannot read ({exc})")
    if problems:
        return problems
    labels, racks = tables["labels.csv"], tables["racks.csv"]
    want = Counter(ids)
    on_rack = {u: r.get("rack", "") for r in racks for u in (r.get("unit_ids") or "").split()}
    for name, got in (("labels.csv", Counter(r.get("id", "") for r in labels)),
                      ("racks.csv", Counter(u for r in racks for u in (r.get("unit_ids") or "").split()))):
        for what, units in (("no row", want - got), ("more than one row", got - want)):
            if units:
                shown = " ".join(sorted(units)[:12])
                problems.append(f"{folder / name}: {sum(units.values())} unit(s) with {what}: {shown}")
    kg = {}
    for r in labels:  # per unit
        if on_rack.get(r.get("id")) not in (None, r.get("rack")):
            problems.append(f"{folder / 'labels.csv'}: unit {r.get('id')} on rack {r.get('rack')}, racks.csv puts it "
                            f"on {on_rack[r.get('id')]}")
        try:
            kg[r.get("id")] = float(r["weight_kg"])
        except (KeyError, TypeError, ValueError):
            problems.append(f"{folder / 'labels.csv'}: unit {r.get('id')}: unreadable weight_kg")
    drawn: Counter = Counter()
    for r in racks:  # a few racks
        units = (r.get("unit_ids") or "").split()
        try:
            w, limit = float(r["weight_kg"]), float(r["max_weight_kg"])
        except (KeyError, TypeError, ValueError):
            problems.append(f"{folder / 'racks.csv'}: rack {r.get('rack')}: unreadable weight_kg or max_weight_kg")
            continue
        total = sum(kg.get(u, 0.0) for u in units)
        if abs(total - w) > 0.05 * (len(units) + 1):
            problems.append(f"{folder / 'racks.csv'}: rack {r.get('rack')}: weight {w:.1f} kg, its units weigh "
                            f"{total:.1f} kg")
        if w > limit and not (len(units) == 1 and r.get("over_limit") == "yes"):
            problems.append(f"{folder / 'racks.csv'}: rack {r.get('rack')}: {w:.1f} kg over its limit {limit:g} kg")
        for sheet in (r.get("label_sheet") or "").split():  # one or a few sheets
            try:
                text = (folder / sheet).read_text(encoding="utf-8")
            except (OSError, UnicodeDecodeError) as exc:
                problems.append(f"{folder / sheet}: cannot read the labels of rack {r.get('rack')} ({exc})")
                continue
            drawn.update(re.findall(r'<g class="label" data-unit="([^"]*)"', text))
    for what, units in (("no label", want - drawn), ("more than one label", drawn - want)):
        if units:
            problems.append(f"{folder}: {sum(units.values())} unit(s) with {what} on the label sheets: "
                            f"{' '.join(sorted(units)[:12])}")
    return problems


def _result(problems: list[str], positions: int, units: int, worst, ref: dict) -> dict:
    out = {"pass": not problems, "positions": positions, "units": units, "problems": problems,
           "largest_deviation_mm": worst, "against": ref["against"]}
    if problems:
        out["why"] = problems[:8] + ([f"... {len(problems) - 8} more problems"] if len(problems) > 8 else [])
    return out
