"""The whole run: input -> optimize -> offset -> CAD -> exports -> report.

:func:`run_pipeline` drives the stages of :mod:`fabricate.stages` in order and
writes everything into ``<out_root>/<name>/``: the files are built in a hidden
temporary folder beside the target that is renamed into place only after the
report and the run marker are written, so a failed or interrupted run never
leaves a folder that looks complete.  What a run may replace (only a finished
run of this tool, only when asked, and a passing one never by a failing one)
is :mod:`fabricate.runfolder`'s decision.

Outcomes (``RunSummary.status`` -> exit code), in this precedence when several
apply: ``error`` 1 (a bug) > ``bad_input`` 2 > ``export_failed`` 4 (files written
but ``check`` failed, marked with ``CHECK_FAILED.txt``) > ``tolerance_not_reached``
3 (results written, marked in ``report.json``, ``report.html`` and a
``TOLERANCE_NOT_REACHED.txt`` file; also when the optimization stalled and no
parts could be built from its mesh) > ``ok`` 0.  Bad input (exit 2) and an
exporter that raises (exit 4) raise the package's errors and write nothing.
"""
from __future__ import annotations

import logging
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from optimize.atomic import remove_part

from . import runfolder, stages
from .config import RunConfig
from .progress import NullProgress
from .report.measures import collect_measures
from .requirements import apply_requirements, warnings

log = logging.getLogger(__name__)

STAGES = ("input", "optimize", "offset", "cad", "structure", "exports", "report")
EXIT_CODES = {"ok": 0, "tolerance_not_reached": 3, "export_failed": 4, "bad_input": 2, "error": 1, "lost": 1}


@dataclass
class RunSummary:
    """How one run ended: one row of a batch table (picklable, JSON-ready via :meth:`as_dict`).

    status : ``ok`` | ``tolerance_not_reached`` | ``export_failed`` | ``bad_input`` | ``error`` |
        ``lost`` (a batch job whose worker process died twice).
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
    notes: list[str] = field(default_factory=list)

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


def run_pipeline(config: RunConfig, out_root: str | Path | None = None, progress=None, *,
                 force: bool = False) -> RunSummary:
    """Run every stage for ``config`` and write ``<out_root>/<config.name>/``.

    out_root : parent folder of the run folder (default ``./outputs``).
    progress : a :class:`fabricate.progress.NullProgress`-like reporter (default: silent).
    force : replace an earlier finished run there (also ``outputs.overwrite: true``); see
        :mod:`fabricate.runfolder` for what a run may replace, and when it writes beside.

    Returns the :class:`RunSummary` (exit code 0, 3 or 4; ``out_dir`` is where it was written).
    Raises ConfigError / MeshError (bad input, exit 2: also a folder in the way or busy),
    ExportError (exit 4), ConvergenceError (exit 3); on any exception nothing is left at the
    target and a previous result stays.
    """
    progress = progress or NullProgress()
    target = run_folder(config, out_root)
    force = bool(force or config.outputs.overwrite)
    t_start = time.perf_counter()
    runfolder.make_parent(target)
    notes = runfolder.clean_stale_parts(target.parent, config.name)
    for note in notes:
        log.info("%s", note)
    with runfolder.run_lock(target):
        previous = runfolder.check_target(target, force)
        tmp = runfolder.new_part(target)
        try:
            ctx = RunContext(config=config, workdir=tmp, progress=progress)
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
            out = ctx["outcome"]
            runfolder.write_marker(tmp, {"name": config.name, "status": out["status"],
                                         "exit_code": out["exit_code"],
                                         "config_sha256": runfolder.config_hash(config)})
            previous = runfolder.check_target(target, force)  # again: a person may have changed it since
            dest, beside = runfolder.publish_run(tmp, target, previous, out["exit_code"])
        except BaseException:
            remove_part(tmp)
            raise
    ctx.timings["total"] = time.perf_counter() - t_start
    summary = _summary(ctx, dest, ctx.timings["total"])
    summary.notes = notes + ([beside] if beside else [])
    if beside:
        summary.message += f"; {beside}"
    log.info("%s: %s in %.1f s -> %s", config.name, summary.status, summary.seconds, dest)
    return summary


def _run_stage(ctx: RunContext, name: str) -> None:
    fn = getattr(stages, f"stage_{name}")
    ctx.progress.start(name)
    t0 = time.perf_counter()
    note = fn(ctx) or ""
    ctx.timings[name] = time.perf_counter() - t0
    ctx.progress.done(name, note)


PRECEDENCE = ("lost", "error", "bad_input", "export_failed", "tolerance_not_reached", "ok")
"""Statuses from the most to the least severe: a run (or a batch) reports the first that applies."""


def worst(statuses) -> str:
    """The status of :data:`PRECEDENCE` that comes first among ``statuses`` (``ok`` when none)."""
    present = set(statuses)
    return next((s for s in PRECEDENCE if s in present), "ok")


def outcome(ctx: RunContext) -> dict[str, Any]:
    """``{"status", "exit_code", "failed": [measure names, "check:<name>", "parts"], "message"}``.

    Every failure found is listed and named in the message; the status is the worst of them
    (:data:`PRECEDENCE`): a failed file check (4) before a missed tolerance (3), because files
    that fail their check must not go to a shop even for a trial.
    """
    measures = ctx.get("measures", {})
    tol_failed = [k for k, m in measures.items() if m.get("enforced") and m.get("pass") is False]
    skipped = ctx.get("cad_skipped")
    if skipped and not tol_failed:
        tol_failed.append("parts")  # no panels or beams could be built: never a pass
    check = ctx.get("check") or {}
    check_failed = [k for k, v in check.get("checks", {}).items()
                    if isinstance(v, dict) and v.get("pass") is False]
    found, parts = [], []
    if check_failed or check.get("pass") is False:
        found.append("export_failed")
        parts.append("output check failed: " + (", ".join(check_failed) or "see report.json"))
    if tol_failed:
        found.append("tolerance_not_reached")
        shown = [k for k in tol_failed if k in measures]
        parts.append("tolerance not reached: " + (", ".join(
            f"{k} {measures[k]['max']:.3g} > {measures[k]['tolerance']:.3g}" for k in shown) or "no parts built"))
        if skipped:
            parts.append(skipped)
    status = worst(found)
    if parts:
        message = "; ".join(parts)
    else:
        built = ctx.get("parts")
        warn = warnings(measures, built.report.get("limits") if built is not None else None)
        message = "every requirement met" + (f"; {len(warn)} warning(s): " + "; ".join(warn)
                                             if warn else ", every tolerance reached")
    failed = tol_failed + [f"check:{k}" for k in check_failed]
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
