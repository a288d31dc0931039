"""``fabricate measure MESH``: every measure of a mesh as JSON or a table."""
from __future__ import annotations

import json
import math

from .units import add_units


def register(sub) -> None:
    p = sub.add_parser("measure", help="print planarity, conical and circular defects and statistics",
                       description="Print every measure of a mesh (OBJ, OFF, PLY) as JSON, "
                                   "or as a readable table with --table.")
    p.add_argument("mesh", help="mesh file (.obj, .off, .ply, .stl, .3dm)")
    p.add_argument("--table", action="store_true", help="a readable table instead of JSON")
    add_units(p, default=None)
    p.set_defaults(handler=run)


def run(args) -> int:
    from optimize.mesh.measures import summary

    from .units import UNIT_TO_MM, read_mm, resolve_units

    args.units = resolve_units(args.mesh, args.units)
    mesh = read_mm(args.mesh, args.units)
    s = summary(mesh)
    s["units"] = {"file": args.units, "mm_per_unit": UNIT_TO_MM[args.units], "lengths": "mm",
                  "areas": "mm2"}
    for note in mesh.notes:
        s.setdefault("notes", []).append(note)
    if not args.table:
        notes: list[str] = []
        out = _finite(s, notes)
        if notes:
            out.setdefault("notes", []).extend(notes)
        print(json.dumps(out, indent=2, allow_nan=False))
        return 0
    from rich.console import Console
    from rich.table import Table

    m = s["mesh"]
    table = Table(title=f"{m['name']}: {m['vertices']} vertices, {m['faces']} faces {m['face_sizes']}")
    for col in ("measure", "max", "mean", "tolerance", "ok", "worst"):
        table.add_column(col)
    for key in ("planarity", "conical", "circular", "fairness"):
        r = s[key]
        table.add_row(key, f"{r['max']:.3g}", f"{r['mean']:.3g}", str(r.get("tolerance", "")),
                      {True: "yes", False: "NO"}.get(r.get("ok"), ""), str(r["worst"]))
    Console().print(table)
    print(f"lengths in mm (file in {args.units}); vertex types: {s['vertex_types']}; edge length {s['edge_length']}; "
          f"angles (deg) {s['angle_deg']}")
    for note in s.get("notes", []):
        print(f"note: {note}")
    return 0


def _finite(value, notes: list, key: str = ""):
    """``value`` with every non-finite float replaced by ``null`` and a line in ``notes``: JSON has
    no NaN or Infinity (an area of a mesh at 1e200 is beyond float64)."""
    if isinstance(value, dict):
        return {k: _finite(v, notes, f"{key}.{k}" if key else str(k)) for k, v in list(value.items())}
    if isinstance(value, list):
        return [_finite(v, notes, f"{key}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, float) and not math.isfinite(value):
        notes.append(f"{key} is {value} (beyond float64), written as null")
        return None
    return value
