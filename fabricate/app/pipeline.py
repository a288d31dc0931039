"""The whole run: input -> optimize -> offset -> CAD -> structure -> exports -> report.

:func:`run_pipeline` drives the stages of :mod:`fabricate.app.stages` in order (each a function
from the config and earlier records to its record, :mod:`fabricate.app.records`) and
writes everything into ``<out_root>/<name>/``: the files are built in a hidden
temporary folder beside the target that is renamed into place only after the
report and the run marker are written, so a failed or interrupted run never
leaves a folder that looks complete.  What a run may replace (only a finished
run of this tool, only when asked, and a passing one never by a failing one)
is :mod:`fabricate.app.runfolder`'s decision.

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
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping

from optimize.atomic import remove_part

from . import runfolder, stages
from .config import RunConfig
from .options import COMMAND
from .progress import NullProgress
from .records import Outcome, RunRecord, frozen
from ..report.measures import collect_measures, name_worst
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
    facts : a batch job's figures from its report.json (:func:`fabricate.app.sweep.job_facts`).
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
    decision: str = ""
    facts: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)


def run_folder(config: RunConfig, out_root: str | Path | None = None) -> Path:
    """``<out_root>/<name>`` (``out_root`` default: ``./outputs``, :data:`fabricate.app.options.COMMAND`)."""
    root = Path(out_root) if out_root is not None else Path.cwd() / COMMAND.out_root
    return root / config.name


def run_pipeline(config: RunConfig, out_root: str | Path | None = None, progress=None, *,
                 force: bool = False) -> RunSummary:
    """Run every stage for ``config`` and write ``<out_root>/<config.name>/``.

    out_root : parent folder of the run folder (default ``./outputs``).
    progress : a :class:`fabricate.app.progress.NullProgress`-like reporter (default: silent).
    force : replace an earlier finished run there (also ``outputs.overwrite: true``); see
        :mod:`fabricate.app.runfolder` for what a run may replace, and when it writes beside.

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
            run = run_stages(config, tmp, progress, t_start)
            progress.start("report")
            t0 = time.perf_counter()
            written = stages.stage_report(run)
            timings = dict(run.timings, report=time.perf_counter() - t0)
            progress.done("report", f"{len(written)} report files")
            out = run.outcome
            runfolder.write_marker(tmp, {"name": config.name, "status": out.status, "exit_code": out.exit_code,
                                         "config_sha256": runfolder.config_hash(config)})
            previous = runfolder.check_target(target, force)  # again: a person may have changed it since
            dest, beside = runfolder.publish_run(tmp, target, previous, out.exit_code)
        except BaseException as exc:
            remove_part(tmp)
            _name_target(exc, tmp, target)
            raise
    timings["total"] = time.perf_counter() - t_start
    summary = _summary(run, dest, timings)
    summary.notes = notes + ([beside] if beside else [])
    if beside:
        summary.message += f"; {beside}"
    log.info("%s: %s in %.1f s -> %s", config.name, summary.status, summary.seconds, dest)
    return summary


def run_stages(config: RunConfig, workdir: Path, progress=None, t_start: float | None = None) -> RunRecord:
    """Every stage up to the report, in order, into ``workdir``: the :class:`RunRecord` the report is
    built from (measures with the requirements applied, the outcome, the timings in s)."""
    progress = progress or NullProgress()
    t_start = time.perf_counter() if t_start is None else t_start
    timings: dict[str, float] = {}

    def stage(name: str, *args, **kwargs):
        fn = getattr(stages, f"stage_{name}")  # looked up at each run (tests replace a stage)
        progress.start(name)
        t0 = time.perf_counter()
        record = fn(*args, **kwargs)
        timings[name] = time.perf_counter() - t0
        progress.done(name, record.line)
        return record

    inp = stage("input", config)
    opt = stage("optimize", config, inp, progress=progress)
    off = stage("offset", config, opt)
    fitted = stages.fitted_depth(config, off)
    if fitted is not None:  # the default beam depth turns faces over here: the largest depth that fits
        config, why = fitted
        off = replace(stage("offset", config, opt), notes=(why,))
        opt = replace(opt, decision=f"{opt.decision} {why}".strip() if opt.decision else "")
    if inp.advice:  # the unit a mesh file was read in looks wrong: said first
        opt = replace(opt, decision=f"{inp.advice} {opt.decision}".strip())
    built = stage("cad", config, opt, off)
    statics = stage("structure", config, off, built)
    files = stage("exports", config, workdir, opt, off, built, statics, progress=progress)
    tol = config.tolerances
    measures = collect_measures(config, inp, opt, off)
    measures.update({k: dict(v) for k, v in statics.measures.items()})
    if built.parts is not None:  # the shop's warnings: a beam longer than a stock bar, a fold beyond the gasket's
        from fabricate.export.bars import bar_measures
        from fabricate.export.gasket import gasket_measures

        measures.update(bar_measures(built.parts, config.outputs.bars.model_dump()))
        measures.update(gasket_measures(built.parts, config.outputs.gasket.model_dump()))
    measures = apply_requirements(measures, off.structure, tol.requirements, opt.target or inp.target,
                                  tol.beam_twist_mm,
                                  tol.closeness_mm)
    name_worst(measures, opt.mesh)
    limits = built.parts.report.get("limits") if built.parts is not None else None
    result = outcome(measures, files.check, built.skipped, limits)
    timings["before_report"] = time.perf_counter() - t_start
    return RunRecord(config=config, workdir=workdir, input=inp, optimize=opt, offset=off, parts=built,
                     structure=statics, exports=files, measures=frozen(measures), outcome=result,
                     timings=frozen(timings))


def _name_target(exc: BaseException, tmp: Path, target: Path) -> None:
    """Say the run folder's own name in the one line of ``exc`` where it names a file in the hidden
    temporary folder the run was writing (``out/.roof.x6_oe.part/model.stl`` -> ``out/roof/model.stl``):
    that folder is gone, the user knows the other."""
    if isinstance(exc, OSError):
        for attr in ("filename", "filename2"):
            name = getattr(exc, attr, None)
            if isinstance(name, str) and str(tmp) in name:
                setattr(exc, attr, name.replace(str(tmp), str(target)))
    elif exc.args and isinstance(exc.args[0], str) and str(tmp) in exc.args[0]:
        exc.args = (exc.args[0].replace(str(tmp), str(target)),) + exc.args[1:]


PRECEDENCE = ("lost", "error", "bad_input", "export_failed", "tolerance_not_reached", "ok")
"""Statuses from the most to the least severe: a run (or a batch) reports the first that applies."""


def worst(statuses) -> str:
    """The status of :data:`PRECEDENCE` that comes first among ``statuses`` (``ok`` when none)."""
    present = set(statuses)
    return next((s for s in PRECEDENCE if s in present), "ok")


def outcome(measures: Mapping[str, Mapping], check: Mapping | None = None, skipped: str | None = None,
            limits: Mapping | None = None) -> Outcome:
    """The :class:`Outcome` of a run from its measures (requirements applied), the output check,
    why no parts were built (None when they were) and the CAD stage's shop limits.

    Every failure found is listed and named in the message; the status is the worst of them
    (:data:`PRECEDENCE`): a failed file check (4) before a missed tolerance (3), because files
    that fail their check must not go to a shop even for a trial.
    """
    measures = measures or {}
    tol_failed = [k for k, m in measures.items() if m.get("enforced") and m.get("pass") is False]
    if skipped and not tol_failed:
        tol_failed.append("parts")  # no panels or beams could be built: never a pass
    check = check or {}
    check_failed = [k for k, v in check.get("checks", {}).items()
                    if isinstance(v, Mapping) and v.get("pass") is False]
    found, parts = [], []
    not_written = [k for k in check_failed if k.startswith("export ")]
    checked = [k for k in check_failed if k not in not_written]
    if not_written:
        found.append("export_failed")
        parts.append("export failed: " + "; ".join(check["checks"][k].get("why") or k for k in not_written))
    if checked or (check.get("pass") is False and not not_written):
        found.append("export_failed")
        parts.append("output check failed: " + (", ".join(checked) or "see report.json"))
    if tol_failed:
        found.append("tolerance_not_reached")
        shown = [k for k in tol_failed if k in measures]
        parts.append("tolerance not reached: " + (", ".join(_exceeds(k, measures[k]) for k in shown)
                                                  or "no parts built"))
        if skipped:
            parts.append(skipped)
    status = worst(found)
    if parts:
        message = "; ".join(parts)
    else:
        warn = warnings(measures, limits)
        message = "every requirement met" + (f"; {len(warn)} warning(s): " + "; ".join(warn)
                                             if warn else ", every tolerance reached")
    moved = moved_sentence(measures)
    if moved:
        message += f"; {moved}"
    failed = tuple(tol_failed + [f"check:{k}" for k in check_failed])
    return Outcome(status=status, exit_code=EXIT_CODES[status], failed=failed, message=message)


def _exceeds(name: str, m: Mapping) -> str:
    """``closeness 312 mm > 100 mm`` for a limit in mm, ``planarity 0.002 > 1e-06`` otherwise."""
    if m.get("tolerance_mm") is not None and m.get("max_mm") is not None:
        return f"{name} {m['max_mm']:,.1f} mm > {m['tolerance_mm']:g} mm"
    return f"{name} {m['max']:.3g} > {m['tolerance']:.3g}"


def moved_sentence(measures: Mapping[str, Mapping]) -> str:
    """How far the design moved and how much rougher it became, for every headline:
    ``design moved up to 77.9 mm (0.45 % of the bounding-box diagonal), 1.3 x the input's roughness``
    ('' when the run did not optimize)."""
    close, rough = measures.get("closeness"), measures.get("roughness")
    if not close or close.get("max_mm") is None:
        return ""
    text = f"design moved up to {close['max_mm']:,.1f} mm ({100 * close['max']:.2f} % of the bounding-box diagonal)"
    if rough and rough.get("max") is not None:
        text += f", {rough['max']:.2g} x the input's roughness"
    return text


def _summary(run: RunRecord, target: Path, timings: dict[str, float]) -> RunSummary:
    out, mesh, measures, parts = run.outcome, run.optimize.mesh, run.measures, run.parts.parts
    return RunSummary(
        name=run.config.name, status=out.status, exit_code=out.exit_code, out_dir=str(target),
        config_file=str(run.config.source) if run.config.source else None,
        faces=mesh.n_faces, vertices=mesh.n_vertices,
        planarity=measures.get("planarity", {}).get("max"),
        conical=measures.get("conical", {}).get("max"),
        parts=stages.count_parts(parts) if parts is not None else None,
        seconds=timings["total"], message=out.message, timings=dict(timings), failed=list(out.failed),
        decision=run.optimize.decision)
