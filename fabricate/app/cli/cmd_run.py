"""``fabricate run CONFIG``: the whole pipeline for one config into ``outputs/<name>/``."""
from __future__ import annotations

import sys
from pathlib import Path

from .args import add_config, add_force, add_out, add_quiet, add_sets, one_value_sets


def register(sub) -> None:
    p = sub.add_parser(
        "run", help="run the whole pipeline for one YAML config",
        description="Input -> subdivide/optimize -> offset -> CAD -> exports -> report, written "
                    "atomically into OUT/<name>/ (a failed or interrupted run leaves no folder that "
                    "looks complete). An existing OUT/<name>/ is replaced only when it is a finished "
                    "run of this tool with no files added or changed, and only with --force (or "
                    "outputs.overwrite: true); a run that misses a tolerance or fails its file check "
                    "never replaces a passing result: it is written beside it as "
                    "OUT/<name>.failed-<time>/.",
        epilog="Exit codes: 0 ok, 2 bad input (also: OUT/<name> in the way or being written by another "
               "run), 3 tolerance not reached (results written, marked in report.json, report.html and "
               "TOLERANCE_NOT_REACHED.txt), 4 export failed (when both, 4), 1 internal error, "
               "130 interrupted.")
    add_config(p, "YAML run configuration (see configs/reference.yaml)")
    add_out(p)
    add_sets(p, "override a config value, e.g. --set parts.glass_thickness=8 (repeatable); a list key "
                "takes a comma list: --set offset.distances=0,-200")
    add_force(p, "replace an earlier finished run in OUT/<name>/ (never a folder this tool did "
                 "not write, nor one with files added or changed since)")
    add_quiet(p)
    p.set_defaults(handler=run)


def run(args) -> int:
    from rich.console import Console

    from fabricate.app.config import load_config
    from fabricate.app.pipeline import STAGES, run_folder, run_pipeline
    from fabricate.app.progress import NullProgress, RichProgress

    sets = one_value_sets(args.sets, "run", "; use fabricate batch for sweeps")
    config = load_config(args.config, overrides=sets)
    err = Console(stderr=True, highlight=False)
    target = run_folder(config, args.out)
    progress = NullProgress() if args.quiet else RichProgress(STAGES, title=f"{config.name} -> {target}",
                                                              console=err)
    with progress:
        summary = run_pipeline(config, args.out, progress=progress, force=args.force)
    for note in summary.notes:
        print(f"note: {note}", file=sys.stderr)
    if summary.decision:  # a user's own mesh: which route was taken, and why
        print(summary.decision)
    target = summary.out_dir
    line = f"{summary.name}: {summary.status} ({summary.message}) in {summary.seconds:.1f} s -> {target}"
    _print_totals(target)
    if summary.exit_code == 0:
        print(line)
        print(f"open {Path(target) / 'report.html'}" if config.outputs.html
              else f"see {Path(target) / 'report.json'}")
    else:
        print(f"warning: {line}; results written and marked", file=sys.stderr)
    return summary.exit_code


def _print_totals(target) -> None:
    """The client's totals (glass m2, sizes, steel m and t) from the run's report.json, if written."""
    from fabricate.report.totals import totals_lines
    from optimize import jsontext

    try:
        totals = jsontext.loads((Path(target) / "report.json").read_text(encoding="utf-8")).get("totals")
    except (OSError, ValueError, AttributeError):
        return
    for text in totals_lines(totals):
        print(text)
