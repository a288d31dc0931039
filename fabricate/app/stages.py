"""The stages of a run, each a thin adapter around the public API of its owner.

Every stage is a function from the config and the records of earlier stages
(:mod:`fabricate.app.records`) to its own record; it calls one stage of the product
(never reimplements it) and puts a one-line note for the progress bar in the
record's ``line``.  Files go into the work folder the pipeline gives the exports.

stage_input(cfg)                                   -> InputRecord
stage_optimize(cfg, input, progress)               -> OptimizeRecord
stage_offset(cfg, optimize)                        -> OffsetRecord
stage_cad(cfg, optimize, offset)                   -> PartsRecord
stage_structure(cfg, offset, parts)                -> StructureRecord
stage_exports(cfg, workdir, optimize, offset, parts, structure, progress) -> ExportsRecord
stage_report(run)                                  -> the report files (names)
"""
from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import Any

import numpy as np

from optimize.errors import ConfigError, ExportError, MeshError

from .config import UNIT_TO_MM
from .progress import NullProgress
from .records import (ExportsRecord, InputRecord, OffsetRecord, OptimizeRecord, PartsRecord, RunRecord,
                      StructureRecord, frozen)

log = logging.getLogger(__name__)


# -- input ---------------------------------------------------------------------
def stage_input(cfg) -> InputRecord:
    """Build or read the input mesh; convert it to mm; decide levels, scheme and target."""
    inp = cfg.input
    kind = inp.kind
    plan: dict[str, Any] = {"kind": kind, "levels": 0, "scheme": "catmull_clark", "target": "conical"}
    surface = None
    if kind == "shape":
        design = inp.shape.design  # built once, when the config was validated
        mesh = design.mesh
        plan.update(levels=int(design.levels), scheme=design.scheme, target=design.target,
                    source=f"built-in design {inp.shape.name}", description=design.description,
                    params=_plain(design.params), units=design.units)
        factor = UNIT_TO_MM[design.units] * cfg.scale  # designs carry their units; `units` is for files
    else:
        from optimize.mesh.io import read_mesh

        path = getattr(inp, kind)
        mesh = read_mesh(path, layer=inp.layer, name=inp.object)  # layer/object: .3dm only
        plan.update(source=str(path), units=cfg.units, levels=2 if kind == "control" else 0)
        factor = cfg.mm_per_unit
        if kind == "surface":
            from optimize.remesh.quads import check_remesh_size, remesh

            surface = mesh  # the optimizer's reference: the user's surface, not the quads
            check_remesh_size(mesh, inp.edge_length, key="input.edge_length", unit=cfg.units)
            mesh, rep = remesh(mesh, inp.edge_length, radius=inp.radius, side=inp.side,
                               irregular=inp.irregular or "faces", with_report=True)
            plan["remesh"] = _plain(dict(rep.as_dict(), faces=mesh.n_faces, vertices=mesh.n_vertices))
    for key, value in (("levels", cfg.subdivision.levels), ("scheme", cfg.subdivision.scheme),
                       ("target", cfg.optimize.target)):
        if value is not None:
            plan[key] = value
    plan.update(scale=cfg.scale, mm_per_unit=factor, faces=mesh.n_faces, vertices=mesh.n_vertices)
    if plan["levels"] == 0 and kind != "surface":  # optimized as it is: quads, not triangles
        from .quads import RUN_HINT, require_quads

        require_quads(mesh, f"input.{kind} {plan['source']}", hint=RUN_HINT)
    if factor != 1.0:
        mesh = mesh.with_vertices(mesh.V * factor)
        if surface is not None:
            surface = surface.with_vertices(surface.V * factor)
    from optimize.mesh.measures import check_range

    # coordinates float64 holds more coarsely than the CAD tolerance (a mesh in the wrong unit, or far from
    # the origin): bad input up front, not a failure of some later stage
    check_range(surface if surface is not None else mesh, f"input.{kind} {plan['source']}",
                resolution=cfg.tolerances.cad_linear_mm, needs="the CAD tolerance")
    advice = unit_advice(cfg, (surface if surface is not None else mesh).bbox_diagonal()) if kind != "shape" else ""
    return InputRecord(mesh=mesh, surface=surface, kind=kind, levels=int(plan["levels"]), scheme=plan["scheme"],
                       target=plan["target"], facts=frozen(plan), notes=tuple(mesh.notes) + ((advice,) if advice else ()),
                       line=f"{plan['source']}: {mesh.n_faces} faces", advice=advice)


PLAUSIBLE_MM = (1_000.0, 2_000_000.0)
"""Bounding-box diagonals (mm) of a roof or facade: outside them a mesh read in a unit nobody gave is
likely in another (a 7.3 m roof drawn in metres, read as mm, is 7.3 mm across)."""


def unit_advice(cfg, diagonal_mm: float) -> str:
    """One sentence when ``units`` was neither given nor stated by the file and the mesh, read in mm,
    is smaller or larger than any roof (:data:`PLAUSIBLE_MM`); '' otherwise.  The run goes on (a model
    may be meant at that size); the sentence leads the run's first paragraph."""
    if "units" in cfg.model_fields_set or cfg.units_note is not None:
        return ""
    lo, hi = PLAUSIBLE_MM
    if lo <= diagonal_mm <= hi:
        return ""
    size = diagonal_mm / cfg.scale
    names = {"cm": "centimetres", "m": "metres", "in": "inches", "ft": "feet"}
    guess = [u for u, f in UNIT_TO_MM.items() if u != "mm" and lo <= size * f <= hi]
    best = "m" if "m" in guess else (guess[0] if guess else None)
    hint = (f"if it is drawn in {names[best]}, set units: {best} ({size * UNIT_TO_MM[best] / 1000:.4g} m across)"
            if best else "if it is drawn in another unit, set units (mm, cm, m, in, ft) or scale")
    return (f"Units not given: the mesh was read in mm, {diagonal_mm:.4g} mm across its bounding box; "
            f"{hint}.")


# -- optimize ------------------------------------------------------------------
def method_for(target: str, method: str) -> str:
    """The optimizer method that runs for ``method`` asked and ``target``: ``strip`` has no default
    solver, so ``default`` means the paper's :data:`optimize.modelling.hierarchy.STRIP_METHOD` there (the one
    place this is decided for ``fabricate run`` and ``fabricate optimize``)."""
    if target == "strip" and method == "default":
        from optimize.modelling.hierarchy import STRIP_METHOD

        return STRIP_METHOD
    return method


def optimizer_call(cfg, target: str) -> tuple[str, dict[str, Any]]:
    """``(method, keyword arguments)`` of the optimizer for the config's ``optimize`` section: the one
    place that decides which method runs.  Target ``strip`` has no default solver: ``default`` means
    the paper's :data:`optimize.modelling.hierarchy.STRIP_METHOD`; the keys of the default method (formulation,
    linear solver, torsion-free beams, convexity) go only where the default method was asked for."""
    opt = cfg.optimize
    method = method_for(target, opt.method)
    kwargs = dict(method=method, fixed=_fixed(opt.fixed), glide_boundary=opt.glide_boundary,
                  fairness=opt.fairness, closeness=opt.closeness, tol=cfg.tolerances.to_tolerances(),
                  max_iter=opt.max_iter)
    if opt.method == "default":  # asked for: the paper's method refuses a formulation other than auto
        kwargs.update(formulation=opt.formulation, linear_solver=opt.linear_solver,
                      torsion_free_beams=opt.torsion_free_beams, convex=opt.convex, refine=opt.refine,
                      rationalize=opt.rationalize)
    return method, kwargs


def stage_optimize(cfg, inp: InputRecord, progress=None) -> OptimizeRecord:
    """Subdivide and perturb to the target (``optimize.modelling.hierarchy.subdivide_and_perturb``;
    ``levels = 0`` optimizes the input itself, target ``"none"`` only subdivides)."""
    progress = progress or NullProgress()
    target, levels = inp.target, inp.levels
    iteration = [0]

    def callback(*args, **kwargs):
        iteration[0] += 1
        info = args[-1] if args and isinstance(args[-1], dict) else kwargs
        p = info.get("planarity") if isinstance(info, dict) else None
        progress.advance("optimize", 1, f"iteration {iteration[0]}"
                         + (f", planarity {p:.2e}" if isinstance(p, float) else ""))

    from optimize.modelling.hierarchy import subdivide_and_perturb

    _, kwargs = optimizer_call(cfg, target)
    hier = subdivide_and_perturb(inp.mesh, levels, scheme=inp.scheme, target=target,
                                 surface=inp.surface, callback=callback, **kwargs)
    level_facts = tuple(frozen(_plain(_level_facts(lv))) for lv in hier.levels)
    level_results = tuple(lv.result for lv in hier.levels)
    result = hier.levels[-1].result
    mesh = hier.mesh
    routes, notes, decision, reached = (), (), "", target
    if inp.kind == "mesh" and levels == 0 and result is not None:  # a user's own quad mesh: which route
        from optimize.remesh.routes import Route

        from .decide import decide

        chosen, tried, decision = decide(cfg, inp, result, kwargs, auto_target=cfg.optimize.target is None,
                                         remesh=cfg.input.remesh or "auto")
        routes = tuple(frozen(_plain(dict(Route(c.name, c.result, c.mesh, c.note).as_dict(), target=c.target,
                                          twist_mm=c.twist_mm, chosen=c is chosen))) for c in tried)
        notes = (decision,)
        mesh, result, reached = chosen.mesh, chosen.result, chosen.target
    line = (f"no optimization ({mesh.n_faces} faces)" if result is None
            else f"{result.status} after {result.nit} iterations" + (f" ({reached})" if reached != target else ""))
    return OptimizeRecord(mesh=mesh, result=result, levels=level_facts, level_results=level_results,
                          routes=routes, notes=notes, line=line, target=reached, decision=decision)


def _level_facts(level) -> dict[str, Any]:
    """One level of the hierarchy for report.json: its facts without the bulky measures, but with
    the strip analysis (kind, singular curve entering the patch, development error) of strip meshes."""
    facts = {k: v for k, v in level.as_dict().items() if k != "measures"}
    strips = (level.measures or {}).get("strips")
    if strips is not None:
        facts["strips"] = strips
    return facts


def _fixed(fixed):
    return np.asarray(fixed, dtype=np.int64) if isinstance(fixed, list) else fixed


# -- offset ----------------------------------------------------------------------
def stage_offset(cfg, opt: OptimizeRecord) -> OffsetRecord:
    """Offset layers, node axes and beams (``fabricate.offset.offset_structure``).

    The axes are fitted by the offset stage from the face normals (``axes=None``):
    at a conical vertex the fit is the cone axis the optimizer found, and at
    boundary and irregular vertices it is better than the optimizer's vertex-normal
    estimate (the offset stage turns free axes so that their beams are planar).
    When the optimizer solved the axes together with planar beams
    (``torsion_free_beams``, meshes with irregular vertices) its axes are used.
    """
    from fabricate.offset import offset_structure

    axes = getattr(opt.result, "beam_axes", None)
    structure = offset_structure(opt.mesh, cfg.layer_distances(), axes=axes, flip=cfg.offset.flip,
                                 tol=cfg.tolerances.to_tolerances())
    kind = "conical" if structure.is_conical else "not conical"
    return OffsetRecord(structure=structure,
                        line=f"{len(structure.layers)} layers, {len(structure.edges)} beams, {kind}")


DEPTH_FIT_MARGIN = 0.9
"""A beam depth fitted to a design takes at most this share of the distance at which its faces turn over."""
AXES_MEET_MARGIN = 0.75
"""... and at most this share of the distance at which the node axes of a beam's two ends meet (deeper,
the beam's far edge shrinks below a quarter of its length at the glass and its end cuts fold)."""
DEPTH_STEP_MM = 10.0
MIN_FITTED_DEPTH_MM = 80.0
"""Below this a fitted beam depth is not offered: the layers are then too close for a beam (the run says why)."""


def _axes_meet_mm(structure) -> float:
    """The smallest distance behind the first layer (mm, along the layers' direction) at which a beam's
    edge shrinks to nothing: the node axes of its two ends meet there (inf when none does)."""
    d0, d1 = structure.distances[0], structure.distances[-1]
    if d1 == d0:
        return np.inf
    E = np.asarray(structure.edges)
    L0, L1 = np.asarray(structure.layers[0]), np.asarray(structure.layers[-1])
    r = L0[E[:, 1]] - L0[E[:, 0]]
    q = (L1[E[:, 1]] - L1[E[:, 0]]) - r  # the edge at layer fraction t is r + t q
    rq, rr = np.einsum("ij,ij->i", r, q), np.einsum("ij,ij->i", r, r)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(rq < 0, -rr / rq, np.inf)  # where its projection on r reaches zero
    return float(np.min(t, initial=np.inf) * abs(d1 - d0))


def fitted_depth(cfg, off: OffsetRecord):
    """``(config, sentence)`` with ``parts.beam_depth`` lowered to fit the design, or None.

    Only when the depth is the default (not in the config) and the layers are the default ones
    (``[0, -beam_depth]``), and the default depth does not fit: a layer past the focal distance
    (faces turn over) or node axes that meet within the depth (beams fold).  The new depth is the
    largest multiple of 10 mm within 90 % of the first and 75 % of the second, at least 80 mm.  A
    depth the user gave is honoured (the run then says what fits, exit 3)."""
    if cfg.offset.distances is not None or "beam_depth" in cfg.parts.model_fields_set:
        return None
    old = cfg.parts.beam_depth
    turned = off.structure.report.get("turned_over") or {"ok": True}
    lo = turned["safe_range_mm"][0] if not turned["ok"] else None
    limits = {"faces turn over": DEPTH_FIT_MARGIN * -lo if lo is not None and lo < 0 else np.inf,
              "node axes of a beam meet": AXES_MEET_MARGIN * _axes_meet_mm(off.structure)}
    why = min(limits, key=limits.get)
    if limits[why] >= old:
        return None
    depth = float(np.floor(limits[why] / DEPTH_STEP_MM) * DEPTH_STEP_MM)
    if depth < MIN_FITTED_DEPTH_MM:
        return None
    fitted = cfg.model_copy(update={"parts": cfg.parts.model_copy(update={"beam_depth": depth})})
    return fitted, (f"Beams {depth:g} mm deep (parts.beam_depth): the default {old:g} mm does not fit this design "
                    f"({why} within {limits[why] / (DEPTH_FIT_MARGIN if why.startswith('faces') else AXES_MEET_MARGIN):.0f} mm "
                    "of the glass); set parts.beam_depth to choose another depth.")


# -- CAD -----------------------------------------------------------------------------
def part_spec(cfg):
    """The :class:`fabricate.cad.PartSpec` of the config's ``parts`` section (the frozen object it
    is derived from, :meth:`fabricate.app.config_section.Section.to_options`)."""
    return cfg.parts.to_options()


def stage_cad(cfg, opt: OptimizeRecord, off: OffsetRecord) -> PartsRecord:
    """Panels, beams and nodes as data (``fabricate.cad.build_parts``).

    An optimization that ended ``folded`` (dented or flipped panels: no glass can be cut from
    them) builds no parts, nor does a mesh from which a part cannot be built with the config's part
    settings (:class:`fabricate.cad.PartError`, naming the part and what to change): either way the
    run goes on to write the mesh, the layers and the report, marked as a missed requirement (exit 3),
    so the result can be inspected and no converged work is lost."""
    from fabricate.cad import build_parts

    spec = part_spec(cfg)
    result = opt.result

    def skipped(msg: str, line: str) -> PartsRecord:
        return PartsRecord(spec=spec, parts=None, skipped=msg, notes=(msg,), line=line)

    if result is not None and result.status == "folded":
        faces = (result.defects.get("folded") or {}).get("faces", [])
        return skipped(f"no panels or beams built: the optimized mesh has {len(faces)} folded face(s) "
                       f"{list(faces)[:8]} (dented or flipped; no glass can be cut from them); see mesh.obj "
                       "and report.json", "skipped: folded panels")
    turned = off.structure.report.get("turned_over") or {"ok": True}
    if not turned["ok"]:  # a layer past the focal distance: panels and beams would cross
        from fabricate.offset.turnover import turnover_sentence

        why = turnover_sentence(turned)
        lo = turned["safe_range_mm"][0]
        if cfg.offset.distances is None and lo is not None and lo < 0:  # the layers are [0, -beam_depth]
            why += (f" The layers come from parts.beam_depth = {spec.beam_depth:g} mm: at most {np.floor(-lo):.0f} mm "
                    "fits this design")
        return skipped("no panels or beams built: " + why, "skipped: offset faces turn over")
    try:
        parts = build_parts(off.structure, spec)
    except (ConfigError, MeshError) as exc:
        # no parts can be cut from this mesh with these part settings: the optimized mesh, the layers
        # and the report are still written, marked as a missed requirement (exit 3) with the reason,
        # so converged work is never lost (the message names the part and what to change)
        if result is not None and not result.success:
            return skipped(f"no panels or beams built from the unconverged mesh (optimization {result.status}: "
                           f"{result.message}): {exc}",
                           f"skipped: optimization {result.status}, parts cannot be built")
        return skipped(f"no panels or beams built from the optimized mesh: {exc}; the mesh, the layers and "
                       "the report are written", "skipped: parts cannot be built")
    from ..cad.parts import unit_id

    counts = {k: len({unit_id(i) for g in parts.of_kind(k) for i in g.ids}) for k in ("panel", "beam", "node")}
    return PartsRecord(spec=parts.spec, parts=parts,  # parts.spec: with a hub sized from the beam angles
                       line=", ".join(f"{n} {k}s" for k, n in counts.items()))


def count_parts(parts) -> int:
    return len(parts)


# -- structure -----------------------------------------------------------------------
def stage_structure(cfg, off: OffsetRecord, parts: PartsRecord) -> StructureRecord:
    """The structural check of the beam frame (``fabricate.structure.run.check_run``) when
    ``structure.check`` is ``report`` or ``enforce``."""
    if cfg.structure.check == "off":
        return StructureRecord(line="off (structure.check: off)")
    if parts.parts is None and parts.skipped:
        msg = f"structure check skipped: {parts.skipped}"
        return StructureRecord(report=frozen({"check": cfg.structure.check, "skipped": msg}), notes=(msg,),
                               line="skipped: no parts")
    from fabricate.structure.outputs import structure_measures
    from fabricate.structure.run import check_run

    opts = cfg.structure.to_options()
    chk, rep, notes, line = check_run(opts, off.structure, parts.spec, parts=parts.parts)
    measures, glass = structure_measures(chk), None
    if opts.glass.check != "off":  # every panel as glass (EN 16612) under the same loads
        from fabricate.structure.glass import check_parts

        glass = check_parts(parts.parts, opts, opts.glass)
        rep = dict(rep, glass=glass.report())
        measures.update(glass.measures())
    return StructureRecord(check=chk, report=frozen(rep), measures=frozen(measures), notes=tuple(notes),
                           line=line, glass=glass)


# -- exports -------------------------------------------------------------------------
EXPORTS = (("step", "model.step", "write_step"), ("stl", "model.stl", "write_stl"),
           ("three_mf", "model.3mf", "write_3mf"), ("dxf", "outlines.dxf", "write_dxf"),
           ("svg", "outlines.svg", "write_svg"), ("flat", "flat.json", "write_flat"),
           ("schedules", "glass_schedule.csv", "write_glass_schedule"),
           ("schedules", "steel_cut_list.csv", "write_steel_cut_list"),
           ("schedules", "node_schedule.csv", "write_node_schedule"),
           ("schedules", "weld_schedule.csv", "write_weld_schedule"),
           ("schedules", "bar_order.csv", "write_bar_order"), ("schedules", "bar_cutting.csv", "write_bar_cutting"),
           ("schedules", "gasket.csv", "write_gasket_schedule"),
           ("glass_order", "glass_order.csv", "write_glass_order"),
           ("layout_plan", "layout_plan.dxf", "write_layout_plan"), ("bom", "bom.csv", "write_bom"),
           ("ifc", "model.ifc", "write_ifc"), ("rhino", "model.3dm", "write_3dm"), ("nc1", "nc1", "write_nc1"),
           ("gltf", "parts.glb", "write_parts_gltf"))


def stage_exports(cfg, workdir: Path, opt: OptimizeRecord, off: OffsetRecord, parts: PartsRecord,
                  statics: StructureRecord, progress=None) -> ExportsRecord:
    """The config as run, meshes, layers and the CAD files into ``workdir``; then the output check in
    the mode ``outputs.check`` asks for (``fabricate.check_fast.run_check``: full, fast or off;
    ``auto`` by the part count), recorded in the check's ``mode``."""
    import yaml

    from optimize.atomic import atomic_open
    from optimize.mesh.io import write_mesh

    progress = progress or NullProgress()
    out = workdir
    files: dict[str, dict] = {}

    cut_batches = None
    export_failed: dict[str, dict] = {}  # file name -> {"pass": False, "why": ...}: an exporter that raised

    def done(check: dict, line: str) -> ExportsRecord:
        return ExportsRecord(files=frozen(files), check=frozen(check), line=line, cut_batches=cut_batches)

    with atomic_open(out / "config.yaml") as fh:
        fh.write(f"# {cfg.name}: the configuration as run (defaults filled in, paths absolute)\n")
        yaml.safe_dump(cfg.as_dict(), fh, sort_keys=False)
    files["config.yaml"] = {"what": "the configuration as run"}
    if cfg.outputs.mesh:
        write_mesh(out / "mesh.obj", opt.mesh)
        files["mesh.obj"] = {"what": "the optimized mesh (mm)"}
    structure = off.structure
    if cfg.outputs.layers:
        for i, d in enumerate(structure.distances):
            name = f"layer_{i}.obj"
            write_mesh(out / name, structure.layer_mesh(i))
            files[name] = {"what": f"offset layer at {d:g} mm"}
    from fabricate import export

    built = parts.parts
    if built is None:  # the CAD stage built nothing (folded panels): meshes only
        return done({"pass": None, "mode": "off", "checks": {}, "skipped": parts.skipped},
                    f"{len(files)} files (no CAD files: {parts.skipped})")
    wanted = [(key, fname, fn) for key, fname, fn in EXPORTS if cfg.outputs.wanted(key)]
    for key, fname, fn in wanted:
        progress.advance("exports", 1, fname)
        try:
            extra = {"rhino": {"structure": structure}, "nc1": {"order": cfg.name or "roof"},
                     "step": {"schema": cfg.outputs.step_schema}}.get(key, {})
            if fn in ("write_steel_cut_list", "write_bar_order", "write_bar_cutting"):  # one cutting plan
                extra = {"bars": cfg.outputs.bars.model_dump()}
            elif fn == "write_gasket_schedule":
                extra = {"gasket": cfg.outputs.gasket.model_dump()}
            facts = getattr(export, fn)(built, out / fname, **extra)
        except Exception as exc:  # an exporter bug or an OCC failure: exit 4, with the file named
            if _write_failed(exc):
                raise  # the disk (full, read-only): nothing more can be written, the report neither
            msg = str(exc) if isinstance(exc, ExportError) else f"{fname}: export failed: {type(exc).__name__}: {exc}"
            msg = msg.replace(f"{out}{os.sep}", "")  # the run folder's own names: the temporary folder goes
            log.warning("%s", msg)
            export_failed[fname] = {"pass": False, "why": msg}
            continue
        files[fname] = dict(facts or {})
        if key == "bom" and statics.check is not None:  # the structure's columns on the beam rows
            from fabricate.structure.outputs import add_bom_columns

            files[fname].update(add_bom_columns(out / fname, statics.check))
    if statics.glass is not None:  # the glass check, per unit
        from fabricate.structure.glass import write_glass_check

        files["glass_check.csv"] = write_glass_check(statics.glass, out / "glass_check.csv")
    if statics.check is not None:  # for the checking engineer: reactions, member end forces, the OpenSees model
        from fabricate.structure.exchange import write_exchange

        files.update(write_exchange(statics.check, out, cfg.name or "roof"))
    if cfg.outputs.wanted("cut_files"):  # one nested DXF and SVG per material and thickness
        progress.advance("exports", 1, "nested cut files")
        nesting = cfg.outputs.nesting.model_dump()
        cut_batches = export.nest_cut_files(built, nesting)  # the report draws the same sheets
        files.update(export.write_cut_files(built, out, nesting, batches=cut_batches))
    if cfg.outputs.stl_parts:  # one STL per part (a welding viewer fuses the touching parts of model.stl)
        progress.advance("exports", 1, "one STL per part")
        files["stl/"] = export.write_stl_parts(built, out / "stl")
    if export_failed:  # the other files and the report are written; the run ends 4, marked, naming them
        names = ", ".join(export_failed)
        return done({"pass": False, "mode": "off", "checks": {f"export {k}": v for k, v in export_failed.items()},
                     "skipped": f"not checked: {names} could not be written"},
                    f"{len(files)} files, EXPORT FAILED: {names}")
    if not cfg.outputs.bom:  # the checks compare every file with the bill of materials
        return done({"pass": None, "mode": "off", "checks": {},
                     "skipped": "bom.csv was not written (outputs.bom: false)"}, f"{len(files)} files, not checked")
    from fabricate.check_fast import run_check

    n_parts = count_parts(built)
    mode = cfg.outputs.check_mode(n_parts)
    progress.advance("exports", 1, f"checking the files ({mode})")
    check = run_check(out, mode, tol=cfg.tolerances.to_tolerances())
    check["mode_asked"] = cfg.outputs.check
    check["parts"] = n_parts
    if mode == "off":
        return done(check, f"{len(files)} files, not checked (outputs.check: off)")
    if "glass_order.csv" in files:  # the order read back and held to the panels it was made from
        from fabricate.export.check_glass_order import check_glass_order

        order = check_glass_order(built, out)
        check.setdefault("checks", {})["glass_order"] = order
        if order["pass"] is False:
            check["pass"] = False
    failed = [k for k, v in check.get("checks", {}).items() if isinstance(v, dict) and v.get("pass") is False]
    return done(check, f"{len(files)} files, " + (f"{mode} check FAILED: {', '.join(failed)}" if failed
                                                  else f"{mode} check passed"))


def _write_failed(exc: BaseException) -> bool:
    """Whether ``exc`` (or what it was raised from) is the file system refusing a write (a full disk,
    a read-only folder): then no later file can be written either."""
    from .cli.exits import WRITE_FAILED

    while exc is not None:
        if isinstance(exc, OSError) and exc.errno in WRITE_FAILED:
            return True
        exc = exc.__cause__
    return False


# -- report ----------------------------------------------------------------------------
def stage_report(run: RunRecord) -> tuple[str, ...]:
    """report.json, pictures, model.glb and report.html (``fabricate.report``), built from ``run``;
    the names of the files written."""
    from fabricate.report import write_report

    try:
        return tuple(write_report(run))
    except (ExportError, MeshError, ConfigError):
        raise
    except Exception as exc:
        raise ExportError(f"report: {type(exc).__name__}: {exc}") from exc


def _plain(value: Any) -> Any:
    """JSON-ready copy (numpy scalars and arrays to Python)."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    return value
