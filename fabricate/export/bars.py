"""Stock bars: the beams and hub tubes a shop saws from bars it buys (``bar_order.csv``, ``bar_cutting.csv``).

Every piece the steel cut list names as sawn from a section (a beam: its one length, end cut to end
cut; a hub tube: its cut between the caps; :func:`fabricate.export.schedules.bar_pieces`) is put on a
stock bar of its section and grade by a one-dimensional cutting plan (:func:`cutting_plan`).

A bar's ``used`` length is its pieces, the kerfs between them and its two end trims; its ``offcut``
the rest of its stock length (:mod:`fabricate.export.bar_plan`).  ``waste`` of an order line: the
bought length that goes into no piece (trims, kerfs and offcuts), in % of the bought length.

A piece longer than the longest stock bar less its two trims is never put on a bar: it is listed under
the bar ``splice needed`` (in ``bar_cutting.csv``, the cut list's ``bar`` column, a line of
``bar_order.csv``) and in the run's warnings (:func:`bar_measures`).

The plan per section and grade: :func:`fabricate.export.bar_plan.cutting_plan`.  :func:`check_bar_plan`
reads the two files back.
"""
from __future__ import annotations

import csv
import logging
import math
import time
from pathlib import Path

from optimize.atomic import atomic_open
from optimize.errors import ExportError, write_error

from .bar_plan import BARS, SPLICE, Bar, Piece, Plan, cutting_plan, options  # noqa: F401 - re-exported

log = logging.getLogger(__name__)

ROUND_MM = 0.05
"""The files write lengths to 0.1 mm: a read-back sum may be this much per piece over the plan's."""
ORDER_COLUMNS = ("section", "grade", "stock_length_mm", "bars", "pieces", "pieces_length_m", "bought_length_m",
                 "mass_kg", "waste_pct")
CUTTING_COLUMNS = ("bar", "section", "grade", "stock_length_mm", "kerf_mm", "end_trim_mm", "pieces", "ids",
                   "lengths_mm", "used_mm", "offcut_mm")


def _f(x: float) -> str:
    return f"{x:.1f}"


def order_rows(plan: Plan) -> list[tuple]:
    """``bar_order.csv``'s rows: per section, grade and stock length the bars to buy, their pieces, the
    pieces' and the bought length (m), mass (kg: bought length x the section's kg/m), waste (%); a
    ``splice needed`` line per section and grade with pieces longer than the longest bar."""
    lines: dict[tuple, list[Bar]] = {}
    for b in plan.bars:
        lines.setdefault((b.section, b.grade, b.stock if b.stock is not None else math.inf), []).append(b)
    rows = []
    for (section, grade, stock), bars in sorted(lines.items()):  # one line per section, grade, stock length
        pieces = [p for b in bars for p in b.pieces]
        length = sum(p.length for p in pieces)
        kg = pieces[0].kg_per_m
        if math.isinf(stock):
            rows.append((section, grade, SPLICE, "", len(pieces), f"{length / 1000:.3f}", "",
                         f"{length / 1000 * kg:.1f}", ""))
            continue
        bought = stock * len(bars)
        rows.append((section, grade, f"{stock:g}", len(bars), len(pieces), f"{length / 1000:.3f}",
                     f"{bought / 1000:.3f}", f"{bought / 1000 * kg:.1f}", f"{100 * (bought - length) / bought:.1f}"))
    return rows


def cutting_rows(plan: Plan) -> list[tuple]:
    """``bar_cutting.csv``'s rows: one per bar (``splice needed``: one per piece too long)."""
    return [(b.id, b.section, b.grade, "" if b.stock is None else f"{b.stock:g}", f"{b.kerf:g}", f"{b.trim:g}",
             len(b.pieces), " ".join(p.id for p in b.pieces), " ".join(_f(p.length) for p in b.pieces),
             _f(b.used), "" if b.stock is None else _f(b.offcut)) for b in plan.bars]


def _write(path: Path, columns, rows, what: str) -> None:
    try:
        with atomic_open(path, "w", encoding="utf-8", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(columns)
            w.writerows(rows)
    except OSError as exc:
        raise write_error(path, what, exc) from exc


def plan_facts(plan: Plan) -> dict:
    """What the report says of a plan: bars per stock length, mass, waste, the pieces to splice."""
    real = [b for b in plan.bars if b.stock is not None]
    bought = sum(b.stock for b in real)
    length = sum(p.length for b in real for p in b.pieces)
    return {"bars": len(real), "pieces": sum(len(b.pieces) for b in plan.bars),
            "by_stock_mm": {f"{s:g}": sum(b.stock == s for b in real) for s in plan.stock_lengths},
            "bought_m": round(bought / 1000, 3), "mass_kg": round(sum(b.stock / 1000 * b.pieces[0].kg_per_m
                                                                        for b in real), 1),
            "waste_pct": round(100 * (bought - length) / bought, 2) if bought else 0.0,
            "splice_needed": [p.id for p in plan.splices]}


def write_bar_order(parts, path, bars: dict | None = None) -> dict:
    """Write ``bar_order.csv`` (atomic) from the plan of ``parts``' bar pieces.  Returns facts."""
    from .schedules import bar_pieces

    t0 = time.perf_counter()
    path = Path(path)
    plan = cutting_plan(bar_pieces(parts), bars)
    rows = order_rows(plan)
    _write(path, ORDER_COLUMNS, rows, "bar order")
    return {"file": path.name, "bytes": path.stat().st_size, "rows": len(rows), **plan_facts(plan),
            "seconds": time.perf_counter() - t0}


def write_bar_cutting(parts, path, bars: dict | None = None) -> dict:
    """Write ``bar_cutting.csv`` (atomic): one row per bar, its pieces in sawing order.  Returns facts."""
    from .schedules import bar_pieces

    t0 = time.perf_counter()
    path = Path(path)
    plan = cutting_plan(bar_pieces(parts), bars)
    rows = cutting_rows(plan)
    _write(path, CUTTING_COLUMNS, rows, "bar cutting plan")
    if plan.splices:
        log.warning("%s: %s", path.name, splice_warning(plan))
    return {"file": path.name, "bytes": path.stat().st_size, "rows": len(rows), "bars": len(rows),
            "splice_needed": [p.id for p in plan.splices], "seconds": time.perf_counter() - t0}


def splice_warning(plan: Plan) -> str:
    """One sentence naming the pieces longer than the longest bar ('' when none)."""
    long = plan.splices
    if not long:
        return ""
    ids = ", ".join(f"{p.id} ({p.length:,.0f} mm)" for p in long[:8]) + (" ..." if len(long) > 8 else "")
    return (f"{len(long)} piece(s) longer than the longest stock bar ({plan.stock_lengths[-1]:g} mm less two "
            f"{plan.trim:g} mm trims): splice needed: {ids}")


def bar_measures(parts, bars: dict | None = None) -> dict:
    """``{"bar_length": ...}``: every beam's one length against the longest stock bar less its two end
    trims (``outputs.bars``), an information measure: a beam beyond it is a warning of the run (splice
    needed), never a failure."""
    from fabricate.report.measures import entry

    from .schedules import bar_pieces

    stocks, _, trim = options(bars)
    beams = [p for p in bar_pieces(parts) if p.id[:1] == "B"]
    if not beams:
        return {}
    return {"bar_length": entry([p.length for p in beams], stocks[-1] - 2 * trim, "mm", "edge",
                                ids=[int(p.id[1:]) - 1 for p in beams],
                                what="a beam's one length against the longest stock bar less two end trims "
                                     "(outputs.bars); longer: splice needed (bar_cutting.csv)")}


def _read(path: Path, what: str) -> list[dict]:
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            return list(csv.DictReader(fh))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise ExportError(f"{path}: cannot read the {what} ({exc})") from None


def is_bar_piece(row: dict) -> bool:
    """Whether a steel cut list row is sawn from a bar: a beam (its own assembly, on a mesh edge) or a hub
    tube."""
    return (row.get("edge", "") != "" and row["id"] == row.get("assembly")) or row.get("member") == "tube"


def check_bar_plan(folder, cut_list: str = "steel_cut_list.csv", cutting: str = "bar_cutting.csv") -> dict:
    """Hold ``bar_cutting.csv`` to the steel cut list beside it: every beam and hub tube of the cut list
    is on exactly one bar, with its cut list length (0.05 mm) and of its section and grade, and the cut
    list's ``bar`` column names that bar; every bar's pieces, the kerfs between them and its two end trims
    fit its stock length (the rounding of the lengths allowed); a piece on ``splice needed`` is longer
    than the longest bar less two trims.  Returns ``{"pass", "bars", "pieces", "splice_needed",
    "problems"}``."""
    folder = Path(folder)
    rows = _read(folder / cutting, "bar cutting plan")
    if not (folder / cut_list).exists():
        return {"pass": False, "problems": [f"{cut_list} is missing: the cutting plan is held to it"]}
    cut = _read(folder / cut_list, "steel cut list")
    problems: list[str] = []
    for name, got, need in ((cutting, rows, CUTTING_COLUMNS), (cut_list, cut, ("id", "length_mm", "bar"))):
        if got and set(need) - set(got[0]):
            return {"pass": False, "problems": [f"{name}: columns {sorted(set(need) - set(got[0]))} missing"]}
    wanted = {r["id"]: r for r in cut if is_bar_piece(r)}
    seen: dict[str, str] = {}
    stocks = [float(r["stock_length_mm"]) for r in rows if r["bar"] != SPLICE and r["stock_length_mm"]]
    longest = max(stocks, default=math.inf)
    for line, r in enumerate(rows, start=2):  # one bar per row
        where = f"{cutting} line {line} ({r['bar']})"
        try:
            ids, lengths = r["ids"].split(), [float(x) for x in r["lengths_mm"].split()]
            kerf, trim = float(r["kerf_mm"]), float(r["end_trim_mm"])
            stock = None if r["bar"] == SPLICE else float(r["stock_length_mm"])
        except ValueError as exc:
            problems.append(f"{where}: {exc}")
            continue
        if len(ids) != len(lengths) or not ids:
            problems.append(f"{where}: {len(ids)} ids and {len(lengths)} lengths")
            continue
        used = sum(lengths) + (len(ids) - 1) * kerf + 2 * trim
        if stock is not None and used > stock + ROUND_MM * len(ids):
            problems.append(f"{where}: pieces {sum(lengths):.1f} + {len(ids) - 1} kerfs of {kerf:g} + 2 trims of "
                            f"{trim:g} = {used:.1f} mm > stock {stock:g} mm")
        if stock is None and math.isfinite(longest) and lengths[0] + 2 * trim <= longest - ROUND_MM:
            problems.append(f"{where}: {ids[0]} ({lengths[0]:.1f} mm) fits a {longest:g} mm bar: no splice needed")
        for pid, L in zip(ids, lengths):  # each piece against its cut list row
            if pid in seen:
                problems.append(f"{where}: {pid} is also on {seen[pid]}")
            seen[pid] = r["bar"]
            c = wanted.get(pid)
            if c is None:
                problems.append(f"{where}: {pid} is no beam or hub tube of {cut_list}")
                continue
            if abs(float(c["length_mm"]) - L) > ROUND_MM + 1e-9:
                problems.append(f"{where}: {pid} {L:.1f} mm, the cut list {c['length_mm']} mm")
            if (c.get("section"), c.get("grade")) != (r["section"], r["grade"]):
                problems.append(f"{where}: {pid} is {c.get('section')} {c.get('grade')} in {cut_list}")
            if c.get("bar") != r["bar"]:
                problems.append(f"{where}: {pid}'s bar in {cut_list} is {c.get('bar')!r}")
    missing = sorted(set(wanted) - set(seen))
    if missing:
        problems.append(f"{len(missing)} piece(s) of {cut_list} on no bar: {', '.join(missing[:10])}")
    return {"pass": not problems, "bars": sum(r["bar"] != SPLICE for r in rows), "pieces": len(seen),
            "splice_needed": sorted(p for p, b in seen.items() if b == SPLICE), "problems": problems[:50]}
