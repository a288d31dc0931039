"""``fabricate batch CONFIG...``: many configs and parameter sweeps in parallel, one summary table."""
from __future__ import annotations

from .args import add_force, add_out, add_sets


def register(sub) -> None:
    from fabricate.app.options import COMMAND

    p = sub.add_parser(
        "batch", help="run many configs / a parameter sweep in parallel and tabulate them",
        description="One job per config and combination of --set values (e.g. "
                    "--set parts.glass_thickness=8,10,12 makes three jobs per config), run in parallel "
                    "worker processes or on a Dask cluster (--scheduler). One failure does not stop the "
                    "others. Prints a summary table and writes it as CSV; "
                    "beside it sweep.csv (in:/out:/img: columns, as Design Explorer reads them), "
                    "pareto.png and pareto.csv (distinct glass shapes against distance moved).",
        epilog="Exit code: 0 when every job is ok, else the code of the worst job, in this order: "
               "1 a job lost (its worker died twice) or crashed (internal error), 2 bad input, "
               "4 export failed, 3 tolerance not reached. A job whose worker process dies is run once "
               "more on its own. 130 interrupted (workers stopped, temporary folders removed).")
    p.add_argument("configs", nargs="+", metavar="CONFIG", help="YAML run configurations")
    add_sets(p, "override / sweep a config value (repeatable; the sweep is the product of all); a list "
                "key's comma list is one list (offset.distances=0,-200), bracket lists to sweep "
                "them (offset.distances=[0,-200],[0,-300])", sweep=True)
    p.add_argument("--workers", type=int, default=COMMAND.workers, metavar="N",
                   help="parallel worker processes (default: one per core, at most one per job)")
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="run on a Dask distributed cluster, e.g. tcp://host:8786 (needs dask[distributed]; "
                        "the workers must see the config and mesh files and the output folder)")
    add_out(p, "run folders")
    add_force(p, "replace earlier finished runs in OUT/<name>/ (as fabricate run --force)")
    p.add_argument("--csv", metavar="PATH", default=None,
                   help="summary table as CSV (default: OUT/batch_summary.csv)")
    p.set_defaults(handler=run)


def run(args) -> int:
    from pathlib import Path

    from rich.console import Console

    from fabricate.app.batch import exit_code, expand_jobs, parse_sets, print_table, run_batch, write_csv
    from optimize.errors import ConfigError

    if args.workers is not None and args.workers < 1:
        raise ConfigError(f"--workers {args.workers}: expected a positive number of worker processes")
    from fabricate.app.runfolder import make_parent

    csv_path = Path(args.csv) if args.csv else Path(args.out) / "batch_summary.csv"
    make_parent(Path(args.out) / "x")
    make_parent(csv_path, "--csv")
    jobs = expand_jobs(args.configs, parse_sets(args.sets))
    err = Console(stderr=True, highlight=False)
    err.print(f"batch: {len(jobs)} job(s)" + (f" on {args.scheduler}" if args.scheduler else ""))

    def done(s):
        err.print(f"  {s.name}: {s.status} ({s.seconds:.1f} s)"
                  + "".join(f"\n    note: {n}" for n in s.notes), highlight=False)

    summaries = run_batch(jobs, args.out, workers=args.workers, scheduler=args.scheduler, on_done=done,
                          force=args.force)
    print_table(summaries)
    path = write_csv(summaries, csv_path)
    print(f"summary: {path}")
    from fabricate.app.sweep import print_sweep, write_sweep

    rows, files = write_sweep(jobs, summaries, csv_path.parent)  # Design Explorer's CSV, the Pareto front
    print_sweep(rows)
    print("sweep: " + ", ".join(str(f) for f in files.values()))
    return exit_code(summaries)
