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

A worker process runs at most :data:`JOBS_PER_WORKER` jobs, then a fresh one takes its place, so
that what native libraries keep after a run (the C heap's fragments, a library's caches) cannot
add up over a long batch.
"""
from __future__ import annotations

import concurrent.futures as cf
import contextlib
import csv
import io
import itertools
import logging
import math
import multiprocessing
import os
import signal
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from optimize.atomic import atomic_open
from optimize.errors import ConfigError, ConicalFabError, writing

from .config import RunConfig, load_config, override_values
from .options import COMMAND
from .pipeline import EXIT_CODES, RunSummary, run_pipeline, worst
from .sweep import job_facts

log = logging.getLogger(__name__)

MAX_NAME = 200
"""Longest job (folder) name in bytes: 255 less the room of ``.<name>.<random>.part`` and
``<name>.failed-<time>-<k>``."""
MAX_JOBS = 10_000
"""A batch of more jobs is refused before any config is read: each job's config is validated before the
first run (about 4 ms each), so 8 million combinations of five swept keys would take nine hours and
their memory before anything ran; split the sweep."""
JOBS_PER_WORKER = 8
"""Jobs a worker process runs before a fresh one replaces it (its imports: about a second).  Workers
that ran every job of a 50-job batch grew from 267 to 415 MB; memory a run's native code keeps grows
a worker for 8 jobs at most.  The batch replaces them itself: Python 3.11's
``ProcessPoolExecutor(max_tasks_per_child=...)`` hangs once a worker retires while jobs wait (CPython
gh-115634)."""
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
    count = len(config_files) * math.prod(len(sets[k]) for k in keys)
    if count > MAX_JOBS:
        sizes = " x ".join([f"{len(config_files)} config{'s' if len(config_files) > 1 else ''}"]
                           + [f"{len(sets[k])} {k}" for k in swept])
        raise ConfigError(f"batch of {count:,} jobs ({sizes}); expected at most {MAX_JOBS:,}: sweep fewer "
                          "values, or split the sweep into several batches")
    jobs: list[Job] = []
    for path in config_files:
        for combo in itertools.product(*(sets[k] for k in keys)) if keys else [()]:
            overrides = dict(zip(keys, combo))
            suffix = "__".join(_label(k, overrides[k]) for k in swept)
            try:
                cfg = load_config(path, overrides=overrides)
                name = f"{cfg.name}__{suffix}" if suffix else cfg.name
                if len(name.encode()) > MAX_NAME:
                    raise ConfigError(f"{path}: job {name[:60]}...: its folder name would be {len(name.encode())} "
                                      f"bytes, expected at most {MAX_NAME} (file systems allow 255 with the "
                                      "temporary and .failed suffixes); sweep fewer keys or give shorter values")
                cfg.name = name
                jobs.append(Job(name, str(path), overrides, cfg))
            except ConicalFabError as exc:
                base = Path(path).stem
                name = f"{base}__{suffix}" if suffix else base
                jobs.append(Job(name if len(name.encode()) <= MAX_NAME else name[:MAX_NAME // 2] + "...",
                                str(path), overrides, error=str(exc)))
    seen: dict[str, str] = {}
    for job in jobs:
        if job.name in seen and job.config is not None:
            raise ConfigError(f"two jobs would write outputs/{job.name}/: {seen[job.name]} and "
                              f"{job.config_file}; give them different names")
        seen[job.name] = job.config_file
    return jobs


def run_job(job: Job, out_root: str, force: bool = False) -> RunSummary:
    """Run one job; never raises (but KeyboardInterrupt): every failure becomes a RunSummary."""
    t0 = time.perf_counter()
    if job.config is None:
        return RunSummary(job.name, "bad_input", EXIT_CODES["bad_input"], config_file=job.config_file,
                          message=job.error or "invalid config")
    try:
        summary = run_pipeline(job.config, out_root, force=force)
        summary.facts = job_facts(summary.out_dir)  # the sweep's figures, read where the job ran
        return summary
    except ConicalFabError as exc:
        status = {2: "bad_input", 3: "tolerance_not_reached", 4: "export_failed"}.get(exc.exit_code, "error")
        return RunSummary(job.name, status, exc.exit_code, config_file=job.config_file,
                          seconds=time.perf_counter() - t0, message=str(exc))
    except Exception as exc:  # noqa: BLE001 - a bug in one job must not stop the batch
        from .cli.exits import classify

        code, line = classify(exc)  # the CLI's table: a bad path is bad input, a bug an internal error
        log.error("%s: %s", job.name, line)
        status = {2: "bad_input", 4: "export_failed"}.get(code, "error")
        return RunSummary(job.name, status, code, config_file=job.config_file, seconds=time.perf_counter() - t0,
                          message=line.removeprefix("error: "))


def make_executor(workers: int, scheduler: str | None = None, *, timeout: float = COMMAND.connect_timeout_s,
                  share: int | None = None) -> tuple[cf.Executor, Callable[[], None]]:
    """A concurrent.futures executor and its closer: worker processes, or a Dask cluster's
    (``timeout`` seconds to connect); ``share``: the processes the cores are shared among (default
    ``workers``: one executor per worker passes the batch's count)."""
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
                                      initializer=_worker_init, initargs=(share or workers,))
    return executor, lambda: executor.shutdown(wait=True, cancel_futures=True)


def _worker_init(workers: int) -> None:
    """In a worker process: let MKL (the optimizer's sparse Cholesky) use this worker's share of
    the cores, so that ``workers`` processes do not each start a thread per core; leave Ctrl-C to
    the batch (it stops the workers and removes what they left)."""
    share = max(1, (os.cpu_count() or 1) // max(1, workers))
    os.environ.setdefault("MKL_NUM_THREADS", str(share))
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def run_batch(jobs: list[Job], out_root: str | Path, *, workers: int | None = None, scheduler: str | None = None,
              on_done: Callable[[RunSummary], None] | None = None, force: bool = False) -> list[RunSummary]:
    """Run ``jobs`` (results in job order); ``on_done`` is called as each finishes.

    A job whose worker process dies (killed, out of memory, a crash in native code) is run once
    more, alone in a fresh worker so that it cannot take healthy jobs down with it; lost twice, it
    ends ``lost`` (exit 1).  Each local worker has an executor of its own (:func:`_workers`), so a
    death fails that worker's job only; a job that failed only beside one (a Dask executor's) is
    run again without counting as an attempt of its own.  Temporary folders of dead workers are
    removed.
    """
    out_root = str(Path(out_root).resolve())
    results: dict[int, RunSummary] = {}
    lost: dict[int, list[str]] = {}
    todo = []
    for i, job in enumerate(jobs):
        if job.config is None:
            results[i] = run_job(job, out_root)
            if on_done:
                on_done(results[i])
        else:
            todo.append(i)
    n = max(1, workers or min(len(todo), os.cpu_count() or 1))

    def finish(i: int, fut: cf.Future) -> bool:
        """Record a finished future; False when its worker was lost."""
        try:
            results[i] = fut.result()
        except cf.CancelledError:
            return False
        except Exception as exc:  # noqa: BLE001 - a dead worker process, a lost Dask task
            text = str(exc).split(". ")[0].split("\n")[0]
            lost.setdefault(i, []).append(f"{type(exc).__name__}: {text}" if text else type(exc).__name__)
            return False
        if i in lost:
            results[i].notes.append(f"its first attempt ended when a worker process died ({lost[i][0]}); "
                                    "this result is from a second attempt, run on its own")
        if on_done:
            on_done(results[i])
        return True

    try:
        if todo and scheduler:
            _round(todo, jobs, out_root, force, scheduler, n, finish)
        elif todo:  # local workers, each replaced after JOBS_PER_WORKER jobs
            _workers(todo, jobs, out_root, force, None, n, finish, JOBS_PER_WORKER)
        again = [i for i in todo if i not in results]
        if again:  # alone, in fresh workers, at most n at a time
            for note in _sweep(out_root, jobs):
                log.warning("%s", note)
            for i in again:
                log.warning("%s: its worker died (%s); running it again on its own", jobs[i].name,
                            "; ".join(lost.get(i, ["pool broken"])))
            _isolated(again, jobs, out_root, force, scheduler, n, finish)
    except KeyboardInterrupt:
        _stop_workers()
        _sweep(out_root, jobs)
        raise
    for i in todo:
        if i not in results:
            why = "; ".join(lost.get(i, [])) or "its worker process died"
            results[i] = RunSummary(jobs[i].name, "lost", EXIT_CODES["lost"], config_file=jobs[i].config_file,
                                    message=f"lost: its worker process died twice ({why}); run it alone "
                                            "(fabricate run) to see why")
            if on_done:
                on_done(results[i])
    for note in _sweep(out_root, jobs):
        log.warning("%s", note)
    return [results[i] for i in range(len(jobs))]


def _round(indices, jobs, out_root, force, scheduler, n, finish) -> None:
    """All ``indices`` on one executor of ``n`` workers (a broken pool fails what it still held)."""
    executor, close = make_executor(n, scheduler)
    try:
        with _workers_ignore_sigint():
            futures = {executor.submit(run_job, jobs[i], out_root, force): i for i in indices}
        for fut in cf.as_completed(futures):
            finish(futures[fut], fut)
    except BaseException:
        _stop_workers()  # before the executor's shutdown, which would wait for the running jobs
        raise
    finally:
        close()


def _isolated(indices, jobs, out_root, force, scheduler, n, finish) -> None:
    """Each of ``indices`` on an executor of its own (one worker), at most ``n`` at a time."""
    _workers(indices, jobs, out_root, force, scheduler, n, finish, 1)


def _workers(indices, jobs, out_root, force, scheduler, n, finish, per_worker: int) -> None:
    """``indices`` on at most ``n`` executors of one worker each: a worker runs up to ``per_worker``
    jobs one after the other, then its executor is closed and the next job starts a fresh one (as
    after a worker that died: a dead worker fails its own job alone)."""
    pending = list(indices)
    idle: list[tuple[Callable, Callable[[], None], int]] = []   # (submit, close, jobs run)
    running: dict[cf.Future, tuple[int, Callable, Callable[[], None], int]] = {}
    try:
        while pending or running:
            while pending and len(running) < n:
                i = pending.pop(0)
                if idle:
                    submit, close, done_jobs = idle.pop()
                else:
                    executor, close = make_executor(1, scheduler, share=n)
                    submit, done_jobs = executor.submit, 0
                with _workers_ignore_sigint():
                    running[submit(run_job, jobs[i], out_root, force)] = (i, submit, close, done_jobs + 1)
            done, _ = cf.wait(running, return_when=cf.FIRST_COMPLETED)
            for fut in done:
                i, submit, close, done_jobs = running.pop(fut)
                if done_jobs < per_worker and not fut.cancelled() and fut.exception() is None:
                    idle.append((submit, close, done_jobs))
                else:
                    close()
                finish(i, fut)
    except BaseException:
        _stop_workers()
        raise
    finally:
        for _, _, close, _ in running.values():
            close()
        for _, close, _ in idle:
            close()


@contextlib.contextmanager
def _workers_ignore_sigint():
    """Worker processes start while SIGINT is ignored, so they ignore it from their first
    instruction (an ignored signal stays ignored across exec; a handler would not): Ctrl-C is the
    batch's to handle, never a traceback from a worker still importing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _stop_workers() -> None:
    """Ctrl-C in a batch: end the worker processes at once (they ignore SIGINT)."""
    children = multiprocessing.active_children()
    for p in children:
        p.terminate()
    for p in children:
        p.join(timeout=1.0)
        if p.is_alive():
            p.kill()


def _sweep(out_root: str, jobs: list[Job]) -> list[str]:
    """Remove the temporary folders dead workers left in ``out_root``; the notes saying so."""
    from .runfolder import clean_stale_parts

    notes = []
    for name in sorted({j.name for j in jobs}):
        notes += clean_stale_parts(Path(out_root), name)
    return notes


def exit_code(summaries: list[RunSummary]) -> int:
    """0 when every job is ok, else the code of the worst job (:data:`fabricate.app.pipeline.PRECEDENCE`):
    a lost or crashed job (1) first, then bad input (2), a failed export (4), a missed tolerance (3)."""
    return EXIT_CODES[worst(s.status for s in summaries)] if summaries else 0


def rows(summaries: list[RunSummary]) -> list[dict[str, Any]]:
    return [{c: getattr(s, c) for c in COLUMNS} for s in summaries]


def write_csv(summaries: list[RunSummary], path: str | Path) -> Path:
    """The summary table as CSV (one row per job, columns :data:`COLUMNS`), atomically."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=COLUMNS)
    writer.writeheader()
    for r in rows(summaries):
        writer.writerow({k: ("" if v is None else f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    text = buf.getvalue()
    with writing(path, "batch summary", needed=len(text.encode())), atomic_open(path, newline="") as fh:
        fh.write(text)
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
    def num(v, f):
        return "" if v is None else format(v, f)

    for s in summaries:
        label = s.status.replace("_", " ").replace("tolerance not reached", "tolerance not met")
        table.add_row(s.name, f"[{style.get(s.status, 'red')}]{label} ({s.exit_code})", num(s.faces, "d"),
                      num(s.planarity, ".2e"), num(s.conical, ".2e"), num(s.parts, "d"), f"{s.seconds:.1f}")
    console = console or Console()
    console.print(table)
    for s in summaries:
        if s.status != "ok":
            console.print(f"[bold]{s.name}[/bold]: {s.message}", highlight=False)
        for note in s.notes:
            console.print(f"[bold]{s.name}[/bold] note: {note}", highlight=False)
