"""The whole run: input -> optimize -> offset -> CAD -> exports -> report.

:func:`run_pipeline` drives the stages of :mod:`fabricate.stages` in order and
writes everything into ``<out_root>/<name>/`` through
:func:`optimize.atomic.atomic_dir`: the files are built in a hidden temporary
folder beside the target that is renamed into place only after the report is
written, so a failed or interrupted run never leaves a folder that looks
complete, and a rerun replaces the previous result only once it is complete.

Outcomes (``RunSummary.status`` -> exit code): ``ok`` 0; ``tolerance_not_reached``
3 (results written, marked in ``report.json``, ``report.html`` and a
``TOLERANCE_NOT_REACHED.txt`` file); ``export_failed`` 4 (files written but
``check`` failed, marked the same way).  Bad input (exit 2) and a failed export
(exit 4) raise the package's errors and write nothing.
"""
from __future__ import annotations

import logging
import os
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from optimize.atomic import atomic_dir

from . import stages
from .config import RunConfig
from .progress import NullProgress
from .report.measures import collect_measures
from .requirements import apply_requirements, warnings

log = logging.getLogger(__name__)

STAGES = ("input", "optimize", "offset", "cad", "structure", "exports", "report")
EXIT_CODES = {"ok": 0, "tolerance_not_reached": 3, "export_failed": 4, "bad_input": 2, "error": 1}


@dataclass
class RunSummary:
    """How one run ended: one row of a batch table (picklable, JSON-ready via :meth:`as_dict`).

    status : ``ok`` | ``tolerance_not_reached`` | ``export_failed`` | ``bad_input`` | ``error``.
    planarity, conical : max defects of the result (relative, radians), None if not reached.
    """

    name: str
    status: str
    exit_code: int
    out_dir: str | None = None
    config_file: str | None = None
    faces: int | None = None
    vertices: int | None = None
    planarity: float | None = None
    conical: float | None = None
    parts: int | None = None
    seconds: float = 0.0
    message: str = ""
    timings: dict[str, float] = field(default_factory=dict)
    failed: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass
class RunContext:
    """What the stages share: the config, the work folder and each stage's results."""

    config: RunConfig
    workdir: Path
    progress: Any
    values: dict[str, Any] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)
    files: dict[str, dict] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    def __getitem__(self, key: str) -> Any:
        return self.values[key]

    def get(self, key: str, default: Any = None) -> Any:
        return self.values.get(key, default)


def run_folder(config: RunConfig, out_root: str | Path | None = None) -> Path:
    """``<out_root>/<name>`` (``out_root`` default: ``./outputs``)."""
    root = Path(out_root) if out_root is not None else Path.cwd() / "outputs"
    return root / config.name


def run_pipeline(config: RunConfig, out_root: str | Path | None = None, progress=None) -> RunSummary:
    """Run every stage for ``config`` and write ``<out_root>/<config.name>/``.

    out_root : parent folder of the run folder (default ``./outputs``).
    progress : a :class:`fabricate.progress.NullProgress`-like reporter (default: silent).

    Returns the :class:`RunSummary` (exit code 0, 3 or 4).  Raises ConfigError /
    MeshError (bad input, exit 2), ExportError (exit 4), ConvergenceError (exit 3);
    on any exception nothing is left at the target and a previous result stays.
    """
    progress = progress or NullProgress()
    target = run_folder(config, out_root)
    t_start = time.perf_counter()
    with atomic_dir(target) as tmp:
        ctx = RunContext(config=config, workdir=Path(tmp), progress=progress)
        for name in STAGES[:-1]:
            _run_stage(ctx, name)
        tol = config.tolerances
        measures = collect_measures(ctx)
        measures.update(ctx.get("structure_measures") or {})
        ctx.values["measures"] = apply_requirements(measures, ctx.get("structure"), tol.requirements,
                                                    ctx["plan"]["target"], tol.beam_twist_mm)
        ctx.values["outcome"] = outcome(ctx)
        ctx.timings["before_report"] = time.perf_counter() - t_start
        _run_stage(ctx, "report")
        _publishable(ctx.workdir)
    ctx.timings["total"] = time.perf_counter() - t_start
    summary = _summary(ctx, target, ctx.timings["total"])
    log.info("%s: %s in %.1f s -> %s", config.name, summary.status, summary.seconds, target)
    return summary


def _publishable(folder: Path) -> None:
    """Give the run folder and its files the usual modes (temporary files are created private)."""
    umask = _umask()
    os.chmod(folder, 0o777 & ~umask)
    for path in folder.rglob("*"):
        os.chmod(path, (0o777 if path.is_dir() else 0o666) & ~umask)


def _umask() -> int:
    """The process umask, read without changing it where possible (threads may be writing files)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except OSError:
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _run_stage(ctx: RunContext, name: str) -> None:
    fn = getattr(stages, f"stage_{name}")
    ctx.progress.start(name)
    t0 = time.perf_counter()
    note = fn(ctx) or ""
    ctx.timings[name] = time.perf_counter() - t0
    ctx.progress.done(name, note)


def outcome(ctx: RunContext) -> dict[str, Any]:
    """``{"status", "exit_code", "failed": [measure names], "message"}`` from the measures and checks."""
    measures = ctx.get("measures", {})
    failed = [k for k, m in measures.items() if m.get("enforced") and m.get("pass") is False]
    check = ctx.get("check") or {}
    check_failed = [k for k, v in check.get("checks", {}).items()
                    if isinstance(v, dict) and v.get("pass") is False]
    if check_failed or check.get("pass") is False:
        status = "export_failed"
        message = "output check failed: " + (", ".join(check_failed) or "see report.json")
        failed = failed + [f"check:{k}" for k in check_failed]
    elif failed:
        status = "tolerance_not_reached"
        message = "tolerance not reached: " + ", ".join(
            f"{k} {measures[k]['max']:.3g} > {measures[k]['tolerance']:.3g}" for k in failed)
        if ctx.get("cad_skipped"):
            message += "; " + ctx.get("cad_skipped")
    else:
        parts = ctx.get("parts")
        warn = warnings(measures, parts.report.get("limits") if parts is not None else None)
        status, message = "ok", "every requirement met" + (f"; {len(warn)} warning(s): " + "; ".join(warn)
                                                           if warn else ", every tolerance reached")
    return {"status": status, "exit_code": EXIT_CODES[status], "failed": failed, "message": message}


def _summary(ctx: RunContext, target: Path, seconds: float) -> RunSummary:
    out = ctx["outcome"]
    mesh = ctx.get("mesh")
    measures = ctx.get("measures", {})
    parts = ctx.get("parts")
    return RunSummary(
        name=ctx.config.name, status=out["status"], exit_code=out["exit_code"], out_dir=str(target),
        config_file=str(ctx.config.source) if ctx.config.source else None,
        faces=mesh.n_faces if mesh is not None else None,
        vertices=mesh.n_vertices if mesh is not None else None,
        planarity=measures.get("planarity", {}).get("max"),
        conical=measures.get("conical", {}).get("max"),
        parts=stages.count_parts(parts) if parts is not None else None,
        seconds=seconds, message=out["message"], timings=dict(ctx.timings), failed=list(out["failed"]))
