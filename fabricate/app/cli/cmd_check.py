"""``fabricate check OUTDIR``: re-validate the files of a finished run."""
from __future__ import annotations

import json


def register(sub) -> None:
    p = sub.add_parser("check", help="re-validate a finished run's STEP, STL, 3MF, DXF, SVG and BOM",
                       description="Read every file of a run folder back and check it against the bill of "
                                   "materials: STEP solids valid (closed planar polyhedra; BRepCheck with --occ) "
                                   "with the analytic volumes and "
                                   "names, STL/3MF manifold with the same volumes, no two parts overlapping, "
                                   "panels touching their beams, DXF audit clean with outlines equal to the "
                                   "3D faces. Exit 0 when every check passes, 4 otherwise; 2 when "
                                   "OUTDIR is not a run's output folder.")
    p.add_argument("outdir", help="a run's output folder (with bom.csv, model.step, ...)")
    p.add_argument("--json", action="store_true", help="print the full result as JSON")
    p.add_argument("--fast", action="store_true",
                   help="do not read the STEP back with OpenCASCADE (nearly all of the time on big "
                        "models): scan its text instead, and check the DXF areas against the BOM")
    p.add_argument("--occ", action="store_true",
                   help="read the STEP back with OpenCASCADE (BRepCheck per solid; about 10 ms a part) "
                        "and audit the DXF with ezdxf, instead of the independent STEP and DXF readers")
    p.set_defaults(handler=run)


def run(args) -> int:
    from fabricate.check_fast import run_check

    require_run_folder(args.outdir)
    from optimize.errors import ConfigError

    if args.fast and args.occ:
        raise ConfigError("fabricate check: --fast and --occ exclude each other (--occ reads the STEP back "
                          "with OpenCASCADE, --fast does not read it back)")
    result = run_check(args.outdir, "fast" if args.fast else "occ" if args.occ else "full")
    if args.json:
        print(json.dumps(result, indent=2, default=str))
    else:
        for name, r in result["checks"].items():
            state = {True: "ok  ", False: "FAIL", None: "skip"}[r.get("pass")]
            detail = r.get("skipped") or _summary(name, r)
            if r.get("pass") is False:
                why = r.get("why") or [r.get("error") or "see --json"]
                detail = "; ".join([why] if isinstance(why, str) else why) + (
                    f" ({detail})" if detail and not r.get("missing") else "")
            print(f"{state} {name:13s} {detail}")
        print(f"{'all checks passed' if result['pass'] else 'FAILED: ' + ', '.join(result['failed'])} "
              f"({result['seconds']:.1f} s)")
    return 0 if result["pass"] else 4


def _summary(name: str, r: dict) -> str:
    keys = {"bom": ("rows", "panel", "beam", "node"), "step": ("solids", "n_invalid", "volume_rel_error_max"),
            "3mf": ("objects", "volume_rel_error_max"), "stl": ("status", "components", "genus", "volume_error_mm3"),
            "intersections": ("box_pairs", "boolean_pairs", "max_volume_mm3", "failed"),
            "bearing": ("pairs", "max_gap_mm", "failed"),
            "dxf": ("outlines", "audit_errors", "area_rel_error_max", "edge_error_mm_max", "failed"),
            "cut": ("files", "sheets", "outlines", "failed"),
            "svg": ("groups", "expected"), "ifc": ("elements", "volume_rel_error_max", "missing", "bad_schema"),
            "3dm": ("elements", "missing", "bad_strings"), "nc1": ("elements", "missing", "bad_files")}.get(name, ())
    return ", ".join(f"{k}={r[k]:.3g}" if isinstance(r.get(k), float) else f"{k}={r.get(k)}" for k in keys)


def require_run_folder(outdir) -> None:
    """ConfigError (exit 2) unless ``outdir`` is a folder a run wrote (its marker, report.json or
    bom.csv): a wrong path is bad input, not a failed check."""
    from pathlib import Path

    from fabricate.app.runfolder import MARKER
    from optimize.errors import ConfigError

    path = Path(outdir)
    if not path.is_dir():
        what = "does not exist" if not path.exists() else "is not a folder"
        raise ConfigError(f"{outdir}: {what}; expected the output folder of a run (with bom.csv, model.step, ...)")
    if not any((path / name).exists() for name in (MARKER, "report.json", "bom.csv")):
        raise ConfigError(f"{outdir}: is not the output folder of a run (no {MARKER}, report.json or bom.csv)")
