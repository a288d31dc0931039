"""Many runs at once: configs times parameter sweeps, in parallel, one table at the end.

``fabricate batch a.yaml b.yaml --set parts.glass_thickness=8,10,12`` makes one
job per config and combination of swept values (the cartesian product of
every ``--set``), runs them in worker processes
(:class:`concurrent.futures.ProcessPoolExecutor`) or, given a scheduler
address, on a Dask distributed cluster (``distributed.Client.get_executor``;
the workers must see the same files), and tabulates name, status, faces,
planarity, conical defect, parts and time, on the terminal and as CSV.

A job that fails (bad config, bad mesh, failed export, a bug, a dead worker)
becomes a row with its status and message; the others carry on.
"""
from __future__ import annotations

import concurrent.futures as cf
import csv
import io
import itertools
import logging
import multiprocessing
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from optimize.atomic import atomic_open
from optimize.errors import ConfigError, ConicalFabError

from .config import RunConfig, load_config, override_values
from .pipeline import EXIT_CODES, RunSummary, run_pipeline

log = logging.getLogger(__name__)

COLUMNS = ("name", "status", "faces", "planarity", "conical", "parts", "seconds", "message", "out_dir")


@dataclass
class Job:
    """One run of a batch: a validated config, or the error that kept it from being one."""

    name: str
    config_file: str
    overrides: dict[str, Any] = field(default_factory=dict)
    config: RunConfig | None = None
    error: str | None = None


def split_values(text: str) -> list[str]:
    """Split ``"8,10,[0, -200]"`` at top-level commas (brackets and quotes keep theirs)."""
    out, depth, quote, cur = [], 0, "", ""
    for ch in text:
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == "," and depth == 0:
            out.append(cur)
            cur = ""
            continue
        cur += ch
    out.append(cur)
    return [v.strip() for v in out]


def parse_sets(items: list[str] | None) -> dict[str, list[Any]]:
    """``["parts.glass_thickness=8,10"]`` -> ``{"parts.glass_thickness": [8, 10]}`` (YAML values)."""
    sets: dict[str, list[Any]] = {}
    for item in items or []:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key or not text.strip():
            raise ConfigError(f"--set {item!r}: expected KEY=VALUE[,VALUE...], e.g. parts.glass_thickness=8,10,12")
        if key in sets:
            raise ConfigError(f"--set {key}: given twice; list all values in one --set {key}=a,b,c")
        sets[key] = override_values(key, split_values(text))  # a list key: the comma list is one list
    return sets


def _label(key: str, value: Any) -> str:
    text = str(value).replace(" ", "")
    text = "".join(c if c.isalnum() or c in "_.=+-" else "_" for c in text)
    return f"{key.split('.')[-1]}={text}"


def expand_jobs(config_files: list[str | Path], sets: dict[str, list[Any]] | None = None) -> list[Job]:
    """One job per config and combination of ``sets`` values; names made unique and folder-safe.

    Raises ConfigError when two jobs would write the same folder.
    """
    sets = sets or {}
    keys = list(sets)
    swept = [k for k in keys if len(sets[k]) > 1]
    jobs: list[Job] = []
    for path in config_files:
        for combo in itertools.product(*(sets[k] for k in keys)) if keys else [()]:
            overrides = dict(zip(keys, combo))
            suffix = "__".join(_label(k, overrides[k]) for k in swept)
            try:
                cfg = load_config(path, overrides=overrides)
                name = f"{cfg.name}__{suffix}" if suffix else cfg.name
                cfg.name = name
                jobs.append(Job(name, str(path), overrides, cfg))
            except ConicalFabError as exc:
                base = Path(path).stem
                jobs.append(Job(f"{base}__{suffix}" if suffix else base, str(path), overrides, error=str(exc)))
    seen: dict[str, str] = {}
    for job in jobs:
        if job.name in seen and job.config is not None:
            raise ConfigError(f"two jobs would write outputs/{job.name}/: {seen[job.name]} and "
                              f"{job.config_file}; give them different names")
        seen[job.name] = job.config_file
    return jobs


def run_job(job: Job, out_root: str) -> RunSummary:
    """Run one job; never raises: every failure becomes a RunSummary with its status."""
    t0 = time.perf_counter()
    if job.config is None:
        return RunSummary(job.name, "bad_input", EXIT_CODES["bad_input"], config_file=job.config_file,
                          message=job.error or "invalid config")
    try:
        return run_pipeline(job.config, out_root)
    except ConicalFabError as exc:
        status = {2: "bad_input", 3: "tolerance_not_reached", 4: "export_failed"}.get(exc.exit_code, "error")
        return RunSummary(job.name, status, exc.exit_code, config_file=job.config_file,
                          seconds=time.perf_counter() - t0, message=str(exc))
    except Exception as exc:  # noqa: BLE001 - a bug in one job must not stop the batch
        log.exception("%s failed", job.name)
        return RunSummary(job.name, "error", 1, config_file=job.config_file, seconds=time.perf_counter() - t0,
                          message=f"unexpected {type(exc).__name__}: {exc}")


def make_executor(workers: int, scheduler: str | None = None, *,
                  timeout: float = 20.0) -> tuple[cf.Executor, Callable[[], None]]:
    """A concurrent.futures executor and its closer: worker processes, or a Dask cluster's
    (``timeout`` seconds to connect)."""
    if scheduler:
        try:
            from distributed import Client
        except ImportError:
            raise ConfigError(f"--scheduler {scheduler}: Dask is not installed "
                              "(pip install 'dask[distributed]')") from None
        try:
            client = Client(scheduler, timeout=f"{timeout}s")
        except (OSError, TimeoutError) as exc:
            raise ConfigError(f"--scheduler {scheduler}: cannot connect to the Dask scheduler ({exc})") from None
        executor = client.get_executor(pure=False)
        return executor, client.close
    executor = cf.ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                                      initializer=_share_cores, initargs=(workers,))
    return executor, lambda: executor.shutdown(wait=True, cancel_futures=True)


def _share_cores(workers: int) -> None:
    """In a worker process: let MKL (the optimizer's sparse Cholesky) use this worker's share of
    the cores, so that ``workers`` processes do not each start a thread per core."""
    share = max(1, (os.cpu_count() or 1) // max(1, workers))
    os.environ.setdefault("MKL_NUM_THREADS", str(share))


def run_batch(jobs: list[Job], out_root: str | Path, *, workers: int | None = None, scheduler: str | None = None,
              on_done: Callable[[RunSummary], None] | None = None) -> list[RunSummary]:
    """Run ``jobs`` (results in job order); ``on_done`` is called as each finishes."""
    out_root = str(Path(out_root).resolve())
    results: dict[int, RunSummary] = {}
    todo = []
    for i, job in enumerate(jobs):
        if job.config is None:
            results[i] = run_job(job, out_root)
            if on_done:
                on_done(results[i])
        else:
            todo.append(i)
    if todo:
        n = workers or min(len(todo), os.cpu_count() or 1)
        executor, close = make_executor(max(1, n), scheduler)
        try:
            futures = {executor.submit(run_job, jobs[i], out_root): i for i in todo}
            for fut in cf.as_completed(futures):
                i = futures[fut]
                try:
                    results[i] = fut.result()
                except Exception as exc:  # noqa: BLE001 - a dead worker process, a lost Dask task
                    results[i] = RunSummary(jobs[i].name, "error", 1, config_file=jobs[i].config_file,
                                            message=f"worker failed: {type(exc).__name__}: {exc}")
                if on_done:
                    on_done(results[i])
        finally:
            close()
    return [results[i] for i in range(len(jobs))]


def exit_code(summaries: list[RunSummary]) -> int:
    """0 when every job is ok, else the largest exit code of a job."""
    return max((s.exit_code for s in summaries), default=0)


def rows(summaries: list[RunSummary]) -> list[dict[str, Any]]:
    return [{c: getattr(s, c) for c in COLUMNS} for s in summaries]


def write_csv(summaries: list[RunSummary], path: str | Path) -> Path:
    """The summary table as CSV (one row per job, columns :data:`COLUMNS`), atomically."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=COLUMNS)
    writer.writeheader()
    for r in rows(summaries):
        writer.writerow({k: ("" if v is None else f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    with atomic_open(path, newline="") as fh:
        fh.write(buf.getvalue())
    return Path(path)


def print_table(summaries: list[RunSummary], console=None) -> None:
    """The summary table on the terminal (rich)."""
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"batch: {sum(s.status == 'ok' for s in summaries)} of {len(summaries)} ok")
    for col, just in (("name", "left"), ("status", "left"), ("faces", "right"), ("planarity", "right"),
                      ("conical", "right"), ("parts", "right"), ("time s", "right")):
        table.add_column(col, justify=just, overflow="fold", no_wrap=col not in ("name", "status"))
    style = {"ok": "green", "tolerance_not_reached": "yellow"}
    for s in summaries:
        num = (lambda v, f: "" if v is None else format(v, f))
        label = s.status.replace("_", " ").replace("tolerance not reached", "tolerance not met")
        table.add_row(s.name, f"[{style.get(s.status, 'red')}]{label} ({s.exit_code})", num(s.faces, "d"),
                      num(s.planarity, ".2e"), num(s.conical, ".2e"), num(s.parts, "d"), f"{s.seconds:.1f}")
    console = console or Console()
    console.print(table)
    for s in summaries:
        if s.status != "ok":
            console.print(f"[bold]{s.name}[/bold]: {s.message}", highlight=False)
