"""Glass build-ups against today's monolithic panel: CAD stage + exports, measured in the same run.

An insulated unit 10/16/66.4 is four solids per panel (outer pane, two plies, the PVB between
them), so every writer has up to four times the panel solids.  Goal (issue 18): the CAD stage
and its files within 3x of the monolithic run.  The dome of ``bench_cad.py`` (``--panels``,
default 5,000) is built and written (STEP, STL, 3MF, DXF, SVG, BOM, flat.json, glass
schedule, IFC, nested cut files) monolithic, insulated, then monolithic again; the ratio is
against the faster of the two monolithic runs (the machine is shared: compare ratios).

    python benchmarks/bench_glass.py --panels 1000
"""
from __future__ import annotations

import argparse
import json
import logging
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
INSULATED = {"type": "insulated", "outer": {"type": "monolithic", "thickness_mm": 10}, "cavity_mm": 16,
             "gas": "argon", "inner": {"type": "laminated", "plies_mm": [6, 6], "interlayer_mm": 1.52}}
WRITERS = (("write_step", "model.step"), ("write_stl", "model.stl"), ("write_3mf", "model.3mf"),
           ("write_dxf", "outlines.dxf"), ("write_svg", "outlines.svg"), ("write_bom", "bom.csv"),
           ("write_flat", "flat.json"), ("write_glass_schedule", "glass_schedule.csv"), ("write_ifc", "model.ifc"))


def one(structure, glass) -> dict:
    from fabricate import export
    from fabricate.cad import PartSpec, build_parts
    from fabricate.app.config_parts import NestingSection

    with tempfile.TemporaryDirectory(prefix="bench_glass_") as tmp:
        out = Path(tmp)
        t0 = time.perf_counter()
        parts = build_parts(structure, PartSpec(glass=glass))
        t1 = time.perf_counter()
        for fn, name in WRITERS:
            getattr(export, fn)(parts, out / name)
        export.write_cut_files(parts, out, NestingSection().model_dump())
        t2 = time.perf_counter()
    return {"build_up": parts.spec.glass.short(), "solids": len(parts), "build_s": round(t1 - t0, 3),
            "export_s": round(t2 - t1, 3), "total_s": round(t2 - t0, 3)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--panels", type=int, default=5000)
    args = ap.parse_args()
    sys.path.insert(0, str(ROOT))
    sys.path.insert(0, str(ROOT / "benchmarks"))
    logging.disable(logging.WARNING)
    from bench_cad import structure

    s = structure(args.panels)
    rows = [one(s, None), one(s, INSULATED), one(s, None)]
    for r in rows:
        print(json.dumps(r), flush=True)
    base = min(rows[0]["total_s"], rows[2]["total_s"])
    print(f"{args.panels} panels: insulated {rows[1]['build_up']} ({rows[1]['solids']} solids) / monolithic "
          f"({rows[0]['solids']} solids) CAD + export = {rows[1]['total_s'] / base:.2f} (goal <= 3.0)")


if __name__ == "__main__":
    main()
