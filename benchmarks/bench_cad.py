"""The CAD stage against a raw OpenCASCADE writer, measured in the same run.

Goal (issue 7): the whole CAD stage (build_parts and every file: STEP, STL,
3MF, DXF, SVG, BOM) for ~5,000 panels plus their ~10,000 beams within 2x of
a raw OpenCASCADE writer of the same 5,000 panels alone (each face polygon
made into a face and extruded by the glass thickness with
BRepBuilderAPI/BRepPrimAPI, named in an XCAF document, written by
STEPCAFControl_Writer with its default settings), and peak memory under 4 GiB.

Each side runs in its own child process (clean peak memory, no shared
caches), one after the other.  Prints a JSON line per side and the ratio.

    python benchmarks/bench_cad.py               # 5,000 panels
    python benchmarks/bench_cad.py --panels 500  # quick
    python benchmarks/bench_cad.py --check       # the file check against the export it checks
    python benchmarks/bench_cad.py --handoff     # also the CAD stage with the hand-off files (issue 18)
    python benchmarks/bench_cad.py --sections    # plate beams against RHS beams on tube hubs (issue 18)
    python benchmarks/bench_cad.py --sections --repeat 3   # three times over, and the medians
    python benchmarks/bench_cad.py --sections --node-sides 6   # the RHS side's hubs as hexagons

``--sections`` (issue 18 item 1): for the railway station (the run's CAD and exports stages) and the
dome of ``--panels`` panels (build_parts and every fabrication writer), in one run: today's plate
beams with mitred ends against RHS beams welded from six plates on tube hubs with two cap plates
(goal: within 3x of plate-only), and the full file check of the RHS files against their export
(goal: not longer); the new side also has insulated glass (``GLASS_INSULATED``).  For the dome the
CPU times of the same steps are printed too (the railway's are the pipeline's wall times only), and
the CAD + export's user and system CPU apart (the system's share is mostly creating files: on a
shared VM its cost per file moves tenfold from one run to the next).

``--check`` (issue 14): for the railway station (configs/railway_station.yaml,
run with the check off) and the dome of ``--panels`` panels, one child process
each writes the files (the run's exports stage / every writer), then times
the fast check and the full check (the STEP read by the independent text
reader) on them, and prints check / export ratios (goal: full <= 1.0);
``--occ`` adds the full check with OpenCASCADE reading the STEP back.  For the dome the
CPU times of the export and of each check (same process, plus the check's child processes: a
big STEP file and the IFC are checked in children beside the other checks) are printed too: on
a machine shared with other work they move far less than wall times (the railway's export is
the run's exports stage, timed by the pipeline in wall time only).

On a shared machine the timings are noisy: compare ratios, not seconds.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def structure(panels: int):
    """A dome of revolution (conical by construction) with about ``panels`` faces, in mm."""
    from fabricate.offset import offset_structure
    from optimize.modelling import shapes

    around = max(8, int(round((2 * panels) ** 0.5)))
    rows = max(2, int(round(panels / around)))
    m = shapes.revolution(shapes.dome_profile(radius=40.0, rise=15.0, k=rows + 1), around, name="bench_dome")
    return offset_structure(m.with_vertices(m.V * 1000.0), (0.0, -200.0))


def run_stage(panels: int, out: Path) -> dict:
    """The whole CAD stage: build_parts, then every writer."""
    from fabricate.cad import PartSpec, build_parts
    from fabricate.export import write_3mf, write_bom, write_dxf, write_step, write_stl, write_svg

    s = structure(panels)
    t0 = time.perf_counter()
    parts = build_parts(s, PartSpec())
    times = {"build_parts": time.perf_counter() - t0}
    for name, fn in (("model.step", write_step), ("model.stl", write_stl), ("model.3mf", write_3mf),
                     ("outlines.dxf", write_dxf), ("outlines.svg", write_svg), ("bom.csv", write_bom)):
        t = time.perf_counter()
        fn(parts, out / name)
        times[name] = time.perf_counter() - t
    return {"side": "cad_stage", "panels": len(parts.panels), "beams": len(parts.beams),
            "seconds": time.perf_counter() - t0, "parts_seconds": {k: round(v, 3) for k, v in times.items()}}


def run_baseline(panels: int, out: Path) -> dict:
    """Raw OpenCASCADE: every face polygon extruded by 10 mm, named, STEPCAFControl default settings."""
    import numpy as np
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon
    from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
    from OCP.gp import gp_Pnt, gp_Vec
    from OCP.STEPCAFControl import STEPCAFControl_Writer
    from OCP.STEPControl import STEPControl_StepModelType
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.TDocStd import TDocStd_Document
    from OCP.TopLoc import TopLoc_Location
    from OCP.XCAFApp import XCAFApp_Application
    from OCP.XCAFDoc import XCAFDoc_DocumentTool
    from OCP.XSControl import XSControl_WorkSession

    s = structure(panels)
    mesh = s.mesh
    polys = mesh.V[mesh.F]
    normals = np.asarray(s.normals)
    t0 = time.perf_counter()
    doc = TDocStd_Document(TCollection_ExtendedString("XmlOcaf"))
    XCAFApp_Application.GetApplication_s().NewDocument(TCollection_ExtendedString("MDTV-XCAF"), doc)
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    top = tool.NewShape()
    for i, (P, n) in enumerate(zip(polys.tolist(), (10.0 * normals).tolist())):
        poly = BRepBuilderAPI_MakePolygon()
        for p in P:
            poly.Add(gp_Pnt(*p))
        poly.Close()
        face = BRepBuilderAPI_MakeFace(poly.Wire(), True).Face()
        solid = BRepPrimAPI_MakePrism(face, gp_Vec(*n)).Shape()
        label = tool.AddShape(solid, False, False)
        TDataStd_Name.Set_s(label, TCollection_ExtendedString(f"P{i + 1:04d}"))
        tool.AddComponent(top, label, TopLoc_Location())
    tool.UpdateAssemblies()
    writer = STEPCAFControl_Writer(XSControl_WorkSession(), False)
    writer.SetNameMode(True)
    writer.Transfer(doc, STEPControl_StepModelType.STEPControl_AsIs)
    writer.Write(str(out / "baseline.step"))
    return {"side": "raw_occ_baseline", "panels": int(mesh.n_faces), "seconds": time.perf_counter() - t0}


def run_handoff(panels: int, out: Path) -> dict:
    """The CAD stage with the fabrication hand-off (issue 18): the files of :func:`run_stage` plus
    flat.json, the three schedules, the nested cut files per material and thickness, the layout plan."""
    from fabricate.app.config import NestingSection
    from fabricate.export import (write_cut_files, write_flat, write_glass_schedule, write_layout_plan,
                                  write_node_schedule, write_steel_cut_list)

    t0 = time.perf_counter()
    base = run_stage(panels, out)
    from fabricate.cad import PartSpec, build_parts

    parts = build_parts(structure(panels), PartSpec())
    times = {}
    for name, fn in (("flat.json", write_flat), ("glass_schedule.csv", write_glass_schedule),
                     ("steel_cut_list.csv", write_steel_cut_list), ("node_schedule.csv", write_node_schedule),
                     ("layout_plan.dxf", write_layout_plan)):
        t = time.perf_counter()
        fn(parts, out / name)
        times[name] = time.perf_counter() - t
    t = time.perf_counter()
    write_cut_files(parts, out, NestingSection().model_dump())
    times["cut files (nested)"] = time.perf_counter() - t
    extra = sum(times.values())
    return {"side": "handoff", "panels": base["panels"], "beams": base["beams"],
            "seconds": base["seconds"] + extra, "stage_seconds": base["seconds"], "handoff_seconds": extra,
            "parts_seconds": {k: round(v, 3) for k, v in times.items()}, "wall": time.perf_counter() - t0}


def print_handoff(results: dict) -> None:
    """Rows of the hand-off side: the previous file set against it, in the same run."""
    h, st = results["handoff"], results["stage"]
    print(f"hand-off: CAD stage with the previous files {st['seconds']:.2f} s; with flat data, schedules, "
          f"nested cut files and layout plan {h['seconds']:.2f} s (of which the hand-off files "
          f"{h['handoff_seconds']:.2f} s); ratio {h['seconds'] / st['seconds']:.2f} (goal <= 3.0)")


def _cpu_with_children() -> float:
    """CPU seconds of this process and of its ended children (the full check reads a big STEP file
    and the IFC in child processes, :mod:`fabricate.check_lanes`: their time counts too)."""
    ch = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + ch.ru_utime + ch.ru_stime


def time_checks(out: Path, export_s: float, occ: bool, export_cpu_s: float | None = None) -> dict:
    """Fast and full check (and OCC with ``occ``) on ``out``, with their ratios to ``export_s``; with
    ``export_cpu_s`` (the export's CPU time in this process) also CPU-time ratios, which other
    processes on a shared machine disturb far less than wall time."""
    from fabricate.check_fast import run_check

    res = {"export_s": round(export_s, 3)}
    if export_cpu_s is not None:
        res["export_cpu_s"] = round(export_cpu_s, 3)
    for mode in ("fast", "full") + (("occ",) if occ else ()):
        t0, c0 = time.perf_counter(), _cpu_with_children()
        r = run_check(out, mode)
        dt, dc = time.perf_counter() - t0, _cpu_with_children() - c0
        res[f"check_{mode}_s"] = round(dt, 3)
        res[f"check_{mode}_per_export"] = round(dt / export_s, 2)
        if export_cpu_s is not None:
            res[f"check_{mode}_cpu_s"] = round(dc, 3)
            res[f"check_{mode}_cpu_per_export"] = round(dc / export_cpu_s, 2)
        res[f"check_{mode}_pass"] = r["pass"]
        res[f"check_{mode}_parts_s"] = {k: v.get("seconds") for k, v in r["checks"].items()}
    return res


def check_railway(out: Path, occ: bool) -> dict:
    """configs/railway_station.yaml run with the check off; its exports stage time is the export."""
    from fabricate.app.config import load_config
    from fabricate.app.pipeline import run_pipeline

    cfg = load_config(ROOT / "configs" / "railway_station.yaml", overrides={"outputs.check": "off"})
    summary = run_pipeline(cfg, out)
    folder = Path(summary.out_dir)
    report = json.loads((folder / "report.json").read_text())
    return {"case": "railway_station", "parts": report["parts"]["total"]["count"],
            **time_checks(folder, report["timings_s"]["exports"], occ)}


def check_dome(panels: int, out: Path, occ: bool) -> dict:
    """The dome of ``panels`` panels: every writer of the exports stage, then the checks."""
    from fabricate.cad import PartSpec, build_parts
    from fabricate.export import write_3mf, write_bom, write_dxf, write_step, write_stl, write_svg

    parts = build_parts(structure(panels), PartSpec())
    t0, c0 = time.perf_counter(), time.process_time()
    for name, fn in (("model.step", write_step), ("model.stl", write_stl), ("model.3mf", write_3mf),
                     ("outlines.dxf", write_dxf), ("outlines.svg", write_svg), ("bom.csv", write_bom)):
        fn(parts, out / name)
    return {"case": f"dome_{panels}", "parts": len(parts),
            **time_checks(out, time.perf_counter() - t0, occ, time.process_time() - c0)}


SECTIONS = {  # --sections (issue 18 item 1): today's plates with mitred ends against welded RHS beams on tube hubs
    "plate": {"parts.beam.section": "plate", "parts.node.connection": "mitre"},
    "rhs": {"parts.beam.section": "rhs", "parts.beam.web_mm": 5.0, "parts.beam.flange_mm": 5.0,
            "parts.beam.flange_width_mm": 100.0, "parts.node.connection": "hub", "parts.node.hub": "tube",
            "parts.node.radius_mm": 110.0, "parts.node.wall_mm": 10.0, "parts.node.cap_mm": 15.0},
}
GLASS_INSULATED: dict = {"parts.glass": {"type": "insulated", "outer": {"type": "monolithic", "thickness_mm": 10.0},
                                          "cavity_mm": 16.0, "inner": {"type": "laminated", "plies_mm": [6.0, 6.0],
                                                                       "interlayer": "PVB", "interlayer_mm": 1.52}}}
"""Insulated glass 10/16/66.4 (four solids per panel) in the new side of the --sections run; the
plate-only side keeps the config's glass (the dome: monolithic 10 mm)."""


def _spec_overrides(variant: str) -> dict:
    return dict(SECTIONS[variant], **(GLASS_INSULATED if variant != "plate" else {}))


def spec_keywords(variant: str) -> dict:
    """``variant``'s overrides as ``PartSpec`` keywords: ``"parts.beam.section"`` -> ``{"beam": {"section": ...}}``."""
    spec: dict = {}
    for key, value in _spec_overrides(variant).items():
        path = key.split(".")[1:]
        d = spec
        for k in path[:-1]:
            d = d.setdefault(k, {})
        d[path[-1]] = value
    return spec


def sections_railway(variant: str, out: Path) -> dict:
    """configs/railway_station.yaml with ``variant``'s beams and nodes: the run's CAD and exports stage
    times (structure check, pictures and the file check off), then the full file check on its files."""
    from fabricate.check_fast import run_check
    from fabricate.app.config import load_config
    from fabricate.app.pipeline import run_pipeline

    over = {"outputs.check": "off", "outputs.pictures": False, "outputs.html": False, "structure.check": "off",
            **_spec_overrides(variant)}
    summary = run_pipeline(load_config(ROOT / "configs" / "railway_station.yaml", overrides=over), out)
    folder = Path(summary.out_dir)
    report = json.loads((folder / "report.json").read_text())
    t = report["timings_s"]
    t0 = time.perf_counter()
    chk = run_check(folder, "full")
    return {"case": "railway_station", "variant": variant, "parts": report["parts"]["total"]["count"],
            "cad_s": t["cad"], "export_s": t["exports"], "cad_export_s": t["cad"] + t["exports"],
            "check_full_s": time.perf_counter() - t0, "check_pass": chk["pass"]}


def sections_dome(variant: str, panels: int, out: Path) -> dict:
    """The bench's dome of ``panels`` panels with ``variant``'s beams and nodes: build_parts and every
    fabrication writer (STEP, STL, 3MF, DXF, SVG, BOM, flat data, schedules, nested cut files, layout
    plan, NC1), then the full file check on those files."""
    from fabricate.cad import PartSpec, build_parts
    from fabricate.check_fast import run_check
    from fabricate.app.config import NestingSection
    from fabricate.export import (write_3mf, write_bom, write_cut_files, write_dxf, write_flat,
                                  write_glass_schedule, write_layout_plan, write_node_schedule, write_step,
                                  write_steel_cut_list, write_stl, write_svg)
    from fabricate.export.nc1 import write_nc1

    spec = spec_keywords(variant)
    sides = int(os.environ.get("BENCH_NODE_SIDES", "0"))
    if sides and variant != "plate":   # --node-sides: the hubs' polygon (the plate-only side has no hubs)
        spec["node_sides"] = sides
    s = structure(panels)
    u0 = resource.getrusage(resource.RUSAGE_SELF)
    t0, c0 = time.perf_counter(), time.process_time()
    parts = build_parts(s, PartSpec(beam_width=80.0, **spec))
    cad, cad_cpu = time.perf_counter() - t0, time.process_time() - c0
    t0, c0 = time.perf_counter(), time.process_time()
    for name, fn in (("model.step", write_step), ("model.stl", write_stl), ("model.3mf", write_3mf),
                     ("outlines.dxf", write_dxf), ("outlines.svg", write_svg), ("bom.csv", write_bom),
                     ("flat.json", write_flat), ("glass_schedule.csv", write_glass_schedule),
                     ("steel_cut_list.csv", write_steel_cut_list), ("node_schedule.csv", write_node_schedule),
                     ("layout_plan.dxf", write_layout_plan)):
        fn(parts, out / name)
    write_cut_files(parts, out, NestingSection().model_dump())
    write_nc1(parts, out / "nc1")
    export, export_cpu = time.perf_counter() - t0, time.process_time() - c0
    u1 = resource.getrusage(resource.RUSAGE_SELF)
    t0, c0 = time.perf_counter(), _cpu_with_children()
    chk = run_check(out, "full")
    return {"case": f"dome_{panels}", "variant": variant, "parts": len(parts), "cad_s": cad, "export_s": export,
            "cad_export_s": cad + export, "check_full_s": time.perf_counter() - t0, "check_pass": chk["pass"],
            "cad_export_cpu_s": cad_cpu + export_cpu, "export_cpu_s": export_cpu,
            "node_sides": parts.spec.node_sides if variant != "plate" else None,
            "cad_export_user_s": u1.ru_utime - u0.ru_utime, "cad_export_system_s": u1.ru_stime - u0.ru_stime,
            "check_full_cpu_s": _cpu_with_children() - c0}


def main_sections(panels: int, repeat: int = 1) -> None:
    """Plate-only against RHS beams on tube hubs, railway station and the dome, in one run; ``repeat``
    times over (the four children in the same order each time), then the median of each ratio.  The
    file system is synced after each child's folder is removed, so that the next child does not pay for
    writing back the last one's gigabytes."""
    runs = []
    for _ in range(repeat):
        rows = {}
        for case in ("railway", "dome"):
            for variant in SECTIONS:
                with tempfile.TemporaryDirectory(prefix="bench_sections_") as tmp:
                    rows[case, variant] = _child(f"sections_{case}_{variant}", panels, tmp)
                os.sync()
        _print_sections(rows)
        runs.append(rows)
    if repeat > 1:
        for case in ("railway", "dome"):
            ratio = [r[case, "rhs"]["cad_export_s"] / r[case, "plate"]["cad_export_s"] for r in runs]
            check = [r[case, "rhs"]["check_full_s"] / r[case, "rhs"]["export_s"] for r in runs]
            user = [r[case, "rhs"]["cad_export_user_s"] / r[case, "plate"]["cad_export_user_s"] for r in runs
                    if "cad_export_user_s" in r[case, "rhs"]]
            print(f"{runs[0][case, 'rhs']['case']}, median of {repeat} runs: RHS / plate-only "
                  f"{statistics.median(ratio):.2f} x (runs {' '.join(f'{x:.2f}' for x in ratio)}; goal <= 3.0); "
                  f"full check / export {statistics.median(check):.2f} x (runs {' '.join(f'{x:.2f}' for x in check)}; "
                  "goal <= 1.0)" + (f"; user CPU RHS / plate-only {statistics.median(user):.2f} x (runs "
                                    f"{' '.join(f'{x:.2f}' for x in user)})" if user else ""))


def _print_sections(rows: dict) -> None:
    glass = "insulated glass 10/16/66.4" if GLASS_INSULATED else "glass as configured"
    for case in ("railway", "dome"):
        p, r = rows[case, "plate"], rows[case, "rhs"]
        hubs = f" ({r['node_sides']}-gons)" if r.get("node_sides") else ""
        print(f"{r['case']}: plate beams, mitred ends ({p['parts']} parts) CAD + export {p['cad_export_s']:.2f} s; "
              f"RHS beams on tube hubs{hubs}, {glass} ({r['parts']} parts) {r['cad_export_s']:.2f} s = "
              f"{r['cad_export_s'] / p['cad_export_s']:.2f} x plate-only (goal <= 3.0); full check "
              f"{r['check_full_s']:.2f} s = {r['check_full_s'] / r['export_s']:.2f} x its export "
              f"{r['export_s']:.2f} s (goal <= 1.0), pass {r['check_pass']}")
        print(f"{r['case']} per part: plate-only {1e3 * p['cad_export_s'] / p['parts']:.2f} ms, RHS "
              f"{1e3 * r['cad_export_s'] / r['parts']:.2f} ms ({r['parts'] / p['parts']:.1f} x the parts)")
        if "cad_export_cpu_s" in r:  # CPU time in the same processes: far less disturbed on a shared machine
            print(f"{r['case']} CPU time: plate-only CAD + export {p['cad_export_cpu_s']:.2f} s; RHS "
                  f"{r['cad_export_cpu_s']:.2f} s = {r['cad_export_cpu_s'] / p['cad_export_cpu_s']:.2f} x plate-only; "
                  f"full check {r['check_full_cpu_s']:.2f} s = {r['check_full_cpu_s'] / r['export_cpu_s']:.2f} x its "
                  f"export {r['export_cpu_s']:.2f} s")
        if "cad_export_user_s" in r:  # the kernel's share (creating files: the noisiest part here) apart
            print(f"{r['case']} CAD + export user CPU: plate-only {p['cad_export_user_s']:.2f} s, RHS "
                  f"{r['cad_export_user_s']:.2f} s = {r['cad_export_user_s'] / p['cad_export_user_s']:.2f} x; "
                  f"system CPU: plate-only {p['cad_export_system_s']:.2f} s, RHS {r['cad_export_system_s']:.2f} s")


def child(side: str, panels: int, out: str, occ: bool = False) -> None:
    sys.path.insert(0, str(ROOT))
    import logging

    logging.disable(logging.WARNING)
    if side == "railway":
        result = check_railway(Path(out), occ)
    elif side == "dome_check":
        result = check_dome(panels, Path(out), occ)
    elif side.startswith("sections_"):
        _, case, variant = side.split("_")
        result = (sections_railway(variant, Path(out)) if case == "railway"
                  else sections_dome(variant, panels, Path(out)))
    else:
        result = {"stage": run_stage, "baseline": run_baseline, "handoff": run_handoff}[side](panels, Path(out))
    result["peak_rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(json.dumps(result))


def _child(side: str, panels: int, out: str, occ: bool = False) -> dict:
    cmd = [sys.executable, __file__, "--child", side, "--panels", str(panels), "--out", out] + (
        ["--occ"] if occ else [])
    done = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, PYTHONPATH=str(ROOT)))
    if done.returncode:   # the child's own words, not just its exit status
        sys.exit(f"bench_cad: the {side} child failed (exit {done.returncode}):\n{done.stderr[-3000:]}")
    line = done.stdout.strip().splitlines()[-1]
    print(line, flush=True)
    return json.loads(line)


def main_check(panels: int, occ: bool) -> None:
    """The check against the export it checks, railway station and the dome, in one run."""
    rows = []
    for side in ("railway", "dome_check"):
        with tempfile.TemporaryDirectory(prefix="bench_check_") as tmp:
            rows.append(_child(side, panels, tmp, occ))
    for r in rows:
        extra = (f", occ {r['check_occ_s']:.2f} s = {r['check_occ_per_export']:.2f} x"
                 if "check_occ_s" in r else "")
        cpu = (f"; CPU time: export {r['export_cpu_s']:.2f} s, fast {r['check_fast_cpu_per_export']:.2f} x, "
               f"full {r['check_full_cpu_per_export']:.2f} x" if "export_cpu_s" in r else "")
        print(f"{r['case']} ({r['parts']} parts): export {r['export_s']:.2f} s; check fast "
              f"{r['check_fast_s']:.2f} s = {r['check_fast_per_export']:.2f} x export, full "
              f"{r['check_full_s']:.2f} s = {r['check_full_per_export']:.2f} x export (goal <= 1.0){extra}{cpu}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--panels", type=int, default=5000)
    ap.add_argument("--check", action="store_true",
                    help="time the fast and full file check against the export (railway station, dome)")
    ap.add_argument("--occ", action="store_true", help="with --check: also the check with OpenCASCADE")
    ap.add_argument("--handoff", action="store_true", help="also time the CAD stage with the hand-off files")
    ap.add_argument("--repeat", type=int, default=1, help="with --sections: run it this many times, then the medians")
    ap.add_argument("--node-sides", type=int, default=0,
                    help="with --sections: the RHS side's hubs as polygons of this many sides (default: the "
                         "parts' node_sides, 24) for the dome")
    ap.add_argument("--sections", action="store_true",
                    help="plate beams with mitred ends against RHS beams on tube hubs: CAD + export and the "
                         "full check, railway station and the dome")
    ap.add_argument("--child", choices=("stage", "baseline", "railway", "dome_check", "handoff")
                    + tuple(f"sections_{c}_{v}" for c in ("railway", "dome") for v in SECTIONS),
                    help=argparse.SUPPRESS)
    ap.add_argument("--out", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child, args.panels, args.out, args.occ)
        return
    if args.check:
        main_check(args.panels, args.occ)
        return
    if args.sections:
        if args.node_sides:
            os.environ["BENCH_NODE_SIDES"] = str(args.node_sides)   # read by the dome's children
        main_sections(args.panels, args.repeat)
        return
    with tempfile.TemporaryDirectory(prefix="bench_cad_") as tmp:
        results = {}
        for side in ("baseline", "stage") + (("handoff",) if args.handoff else ()):
            results[side] = _child(side, args.panels, tmp)
        sizes = {p.name: p.stat().st_size for p in Path(tmp).iterdir()}
    stage, base = results["stage"], results["baseline"]
    ratio = stage["seconds"] / base["seconds"]
    print(f"files (bytes): {sizes}")
    print(f"CAD stage {stage['panels']} panels + {stage['beams']} beams: {stage['seconds']:.2f} s, "
          f"peak {stage['peak_rss_mib']:.0f} MiB; raw OCC {base['panels']} panels: {base['seconds']:.2f} s, "
          f"peak {base['peak_rss_mib']:.0f} MiB")
    print(f"ratio CAD stage / raw OCC writer = {ratio:.2f} (goal <= 2.0); peak memory "
          f"{stage['peak_rss_mib'] / 1024:.2f} GiB (goal < 4 GiB)")
    if "handoff" in results:
        print_handoff(results)


if __name__ == "__main__":
    main()
