"""The structural check against the CAD stage of the same run, and the share spent in OpenSees.

Goal (issue 20): model build + solve + results for the railway station (1,336 beams) and a
10,000-beam structure in seconds, with the time inside OpenSees printed beside ours; the check
must not be what makes a run slow: under the time of the CAD stage of the same run.

- ``railway_station``: ``fabricate run configs/railway_station.yaml`` as shipped (structure.check:
  enforce), in-process; the stage timings of that run (``cad`` is build_parts, ``exports`` the
  files and their check) and the structure's own breakdown from report.json.
- ``dome_10k``: a dome of revolution (conical by construction) with about 10,000 beams, offset
  200 mm: ``build_parts`` (the CAD stage) and ``check_structure`` timed in the same process.

    python benchmarks/bench_structure.py            # both
    python benchmarks/bench_structure.py --quick    # the 10,000-beam case only

On a shared machine the timings are noisy: compare the ratios, not the seconds.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def line(name: str, beams: int, s: dict, cad: float, extra: dict | None = None) -> dict:
    row = {"case": name, "beams": beams, "structure_s": round(s["total"], 3), "opensees_s": s["opensees"],
           "opensees_share": round(s["opensees"] / s["total"], 2) if s["total"] else None,
           "ours_s": s["ours"], "model_s": s["model"], "opensees_build_s": s.get("opensees_build"),
           "opensees_solve_s": s.get("opensees_solve"), "opensees_read_s": s.get("opensees_read"),
           "cad_stage_s": round(cad, 3), "structure_over_cad": round(s["total"] / cad, 2) if cad else None}
    row.update(extra or {})
    print(json.dumps(row))
    return row


def railway_station() -> dict:
    from fabricate.app.config import load_config
    from fabricate.app.pipeline import run_pipeline

    cfg = load_config(ROOT / "configs" / "railway_station.yaml")
    with tempfile.TemporaryDirectory() as tmp:
        summary = run_pipeline(cfg, tmp)
        rep = json.loads((Path(tmp) / cfg.name / "report.json").read_text())
    t = summary.timings
    s = dict(rep["structure"]["seconds"])
    return line("railway_station", rep["structure"]["elements"], s, t["cad"],
                {"structure_stage_s": round(t["structure"], 3), "exports_s": round(t["exports"], 3),
                 "structure_over_cad_plus_exports": round(t["structure"] / (t["cad"] + t["exports"]), 3),
                 "status": summary.status, "max_utilization": round(rep["structure"]["utilization"]["max"], 3)})


def dome(beams: int = 10000) -> dict:
    from fabricate.cad import PartSpec, build_parts
    from fabricate.app.config import parse_config
    from fabricate.offset import offset_structure
    from fabricate.structure.check import check_structure
    from optimize.modelling import shapes

    around = int(round((beams / 2) ** 0.5 * 1.4))
    rows = max(2, int(round(beams / (2 * around))))
    m = shapes.revolution(shapes.dome_profile(radius=60.0, rise=20.0, k=rows + 1), around, name="bench_dome")
    s = offset_structure(m.with_vertices(m.V * 1000.0), (0.0, -300.0))
    spec = PartSpec(glass_thickness=12.0, beam_width=80.0, beam_depth=300.0)
    opt = parse_config({"input": {"shape": {"name": "dome"}},
                        "structure": {"check": "report", "section": {"shape": "rhs", "depth": 300, "width": 100,
                                                                      "web": 8}}}, source=Path("bench.yaml"))
    opt = opt.structure.to_options()
    t0 = time.perf_counter()
    build_parts(s, spec)
    cad = time.perf_counter() - t0
    chk = check_structure(s, opt, spec)
    return line("dome_10k", chk.frame.n_elements, chk.seconds, cad,
                {"max_utilization": round(chk.max_utilization, 3),
                 "equilibrium": max(chk.results.equilibrium.values())})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="only the 10,000-beam dome")
    ap.add_argument("--beams", type=int, default=10000)
    args = ap.parse_args()
    rows = [dome(args.beams)]
    if not args.quick:
        rows.insert(0, railway_station())
    for r in rows:
        print(f"{r['case']}: {r['beams']} beams, structure {r['structure_s']:.2f} s "
              f"(OpenSees {r['opensees_s']:.2f} s = {100 * (r['opensees_share'] or 0):.0f}%, ours {r['ours_s']:.2f} s); "
              f"CAD stage {r['cad_stage_s']:.2f} s; structure / CAD = {r['structure_over_cad']}")


if __name__ == "__main__":
    main()
