"""``fabricate batch CONFIG...``: many configs and parameter sweeps in parallel, one summary table."""
from __future__ import annotations


def register(sub) -> None:
    p = sub.add_parser(
        "batch", help="run many configs / a parameter sweep in parallel and tabulate them",
        description="One job per config and combination of --set values (e.g. "
                    "--set parts.glass_thickness=8,10,12 makes three jobs per config), run in parallel "
                    "worker processes or on a Dask cluster (--scheduler). One failure does not stop the "
                    "others. Prints a summary table and writes it as CSV.",
        epilog="Exit code: 0 when every job is ok, else the largest exit code of a job "
               "(2 bad input, 3 tolerance not reached, 4 export failed, 1 unexpected error).")
    p.add_argument("configs", nargs="+", metavar="CONFIG", help="YAML run configurations")
    p.add_argument("--set", metavar="KEY=V1[,V2...]", action="append", default=[], dest="sets",
                   help="override / sweep a config value (repeatable; the sweep is the product of all); a list "
                        "key's comma list is one list (offset.distances=0,-200), bracket lists to sweep "
                        "them (offset.distances=[0,-200],[0,-300])")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="parallel worker processes (default: one per core, at most one per job)")
    p.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="run on a Dask distributed cluster, e.g. tcp://host:8786 (needs dask[distributed]; "
                        "the workers must see the config and mesh files and the output folder)")
    p.add_argument("--out", metavar="DIR", default="outputs", help="parent folder of the run folders")
    p.add_argument("--csv", metavar="PATH", default=None,
                   help="summary table as CSV (default: OUT/batch_summary.csv)")
    p.set_defaults(handler=run)


def run(args) -> int:
    from pathlib import Path

    from rich.console import Console

    from fabricate.batch import exit_code, expand_jobs, parse_sets, print_table, run_batch, write_csv
    from optimize.errors import ConfigError

    if args.workers is not None and args.workers < 1:
        raise ConfigError(f"--workers {args.workers}: expected a positive number of worker processes")
    jobs = expand_jobs(args.configs, parse_sets(args.sets))
    err = Console(stderr=True, highlight=False)
    err.print(f"batch: {len(jobs)} job(s)" + (f" on {args.scheduler}" if args.scheduler else ""))

    def done(s):
        err.print(f"  {s.name}: {s.status} ({s.seconds:.1f} s)")

    summaries = run_batch(jobs, args.out, workers=args.workers, scheduler=args.scheduler, on_done=done)
    print_table(summaries)
    path = write_csv(summaries, Path(args.csv) if args.csv else Path(args.out) / "batch_summary.csv")
    print(f"summary: {path}")
    return exit_code(summaries)
