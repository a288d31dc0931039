"""The stages of a run, each a thin adapter around the public API of its owner.

Every ``stage_<name>(ctx)`` reads what earlier stages left in
``ctx.values``, calls one stage of the product (never reimplements it), stores
its results and returns a one-line note for the progress bar.  ``ctx`` is a
:class:`fabricate.pipeline.RunContext`; files go into ``ctx.workdir``.

input    -> values["input_mesh"] (mm), ["plan"] (levels, scheme, target, source facts)
optimize -> ["mesh"] (final), ["result"] (OptimizeResult or None), ["levels"] (hierarchy facts)
offset   -> ["structure"] (OffsetStructure)
cad      -> ["parts"] (Parts)
structure -> ["statics"] (StructureCheck or None), ["statics_report"], ["structure_measures"]
exports  -> files in the work folder, ctx.files facts, ["check"] (with its "mode": full | fast | off)
report   -> ["measures"], report.json, pictures, model.glb, report.html
"""
from __future__ import annotations

import logging
from typing import Any

import numpy as np

from optimize.errors import ConfigError, ExportError, MeshError

from .config import UNIT_TO_MM

log = logging.getLogger(__name__)


# -- input ---------------------------------------------------------------------
def stage_input(ctx) -> str:
    """Build or read the input mesh; convert it to mm; decide levels, scheme and target."""
    cfg = ctx.config
    inp = cfg.input
    kind = inp.kind
    plan: dict[str, Any] = {"kind": kind, "levels": 0, "scheme": "catmull_clark", "target": "conical"}
    if kind == "shape":
        from optimize.designs import DESIGNS

        design = DESIGNS[inp.shape.name](**inp.shape.params)  # parameters checked with the config
        mesh = design.mesh
        plan.update(levels=int(design.levels), scheme=design.scheme, target=design.target,
                    source=f"built-in design {inp.shape.name}", description=design.description,
                    params=_plain(design.params), units=design.units)
        factor = UNIT_TO_MM[design.units] * cfg.scale  # designs carry their units; `units` is for files
    else:
        from optimize.io import read_mesh

        path = getattr(inp, kind)
        mesh = read_mesh(path, layer=inp.layer, name=inp.object)  # layer/object: .3dm only
        plan.update(source=str(path), units=cfg.units, levels=2 if kind == "control" else 0)
        factor = cfg.mm_per_unit
        if kind == "surface":
            from optimize.remesh import remesh

            ctx.values["surface"] = mesh  # the optimizer's reference: the user's surface, not the quads
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
        if "surface" in ctx.values:
            ctx.values["surface"] = ctx.values["surface"].with_vertices(ctx.values["surface"].V * factor)
    ctx.values["input_mesh"] = mesh
    ctx.values["plan"] = plan
    ctx.notes.extend(mesh.notes)
    return f"{plan['source']}: {mesh.n_faces} faces"


# -- optimize ------------------------------------------------------------------
def stage_optimize(ctx) -> str:
    """Subdivide and perturb to the target (``optimize.hierarchy.subdivide_and_perturb``;
    ``levels = 0`` optimizes the input itself, target ``"none"`` only subdivides)."""
    cfg, plan = ctx.config, ctx["plan"]
    mesh = ctx["input_mesh"]
    opt = cfg.optimize
    target, levels = plan["target"], plan["levels"]
    iteration = [0]

    def callback(*args, **kwargs):
        iteration[0] += 1
        info = args[-1] if args and isinstance(args[-1], dict) else kwargs
        p = info.get("planarity") if isinstance(info, dict) else None
        ctx.progress.advance("optimize", 1, f"iteration {iteration[0]}"
                             + (f", planarity {p:.2e}" if isinstance(p, float) else ""))

    from optimize.hierarchy import subdivide_and_perturb

    kwargs = dict(method=opt.method, fixed=_fixed(opt.fixed), glide_boundary=opt.glide_boundary,
                  fairness=opt.fairness, closeness=opt.closeness, tol=cfg.tolerances.to_tolerances(),
                  max_iter=opt.max_iter, callback=callback)
    if opt.method == "default":
        kwargs.update(formulation=opt.formulation, linear_solver=opt.linear_solver,
                      torsion_free_beams=opt.torsion_free_beams, convex=opt.convex)
    hier = subdivide_and_perturb(mesh, levels, scheme=plan["scheme"], target=target,
                                 surface=ctx.values.get("surface"), **kwargs)
    ctx.values["levels"] = [_plain(_level_facts(lv)) for lv in hier.levels]
    ctx.values["level_results"] = [lv.result for lv in hier.levels]
    result = hier.levels[-1].result
    mesh = hier.mesh
    if cfg.input.kind == "mesh" and cfg.input.remesh != "never" and levels == 0 and result is not None:
        from optimize.routes import optimize_routes  # input.remesh: the remeshed route too

        kwargs.pop("callback")
        chosen, routes = optimize_routes(ctx["input_mesh"], target, remesh=cfg.input.remesh,
                                         original=result, **kwargs)
        plan["routes"] = _plain([r.as_dict() for r in routes])
        ctx.notes.extend(r.line() for r in routes)
        mesh, result = chosen.mesh, chosen.result
    ctx.values["mesh"] = mesh
    ctx.values["result"] = result
    if result is None:
        return f"no optimization ({mesh.n_faces} faces)"
    return f"{result.status} after {result.nit} iterations"


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
def stage_offset(ctx) -> str:
    """Offset layers, node axes and beams (``fabricate.offset.offset_structure``).

    The axes are fitted by the offset stage from the face normals (``axes=None``):
    at a conical vertex the fit is the cone axis the optimizer found, and at
    boundary and irregular vertices it is better than the optimizer's vertex-normal
    estimate (the offset stage turns free axes so that their beams are planar).
    When the optimizer solved the axes together with planar beams
    (``torsion_free_beams``, meshes with irregular vertices) its axes are used.
    """
    from fabricate.offset import offset_structure

    result = ctx.get("result")
    axes = getattr(result, "beam_axes", None)
    structure = offset_structure(ctx["mesh"], ctx.config.layer_distances(), axes=axes,
                                 flip=ctx.config.offset.flip, tol=ctx.config.tolerances.to_tolerances())
    ctx.values["structure"] = structure
    kind = "conical" if structure.is_conical else "not conical"
    return f"{len(structure.layers)} layers, {len(structure.edges)} beams, {kind}"


# -- CAD -----------------------------------------------------------------------------
def stage_cad(ctx) -> str:
    """Panels, beams and nodes as data (``fabricate.cad.build_parts``).

    An optimization that ended ``folded`` (dented or flipped panels: no glass can be cut from
    them) builds no parts: the run goes on to write the mesh, the layers and the report, marked
    as a missed tolerance (exit 3), so the result can be inspected."""
    from fabricate.cad import PartSpec, build_parts

    spec = PartSpec(**ctx.config.parts.model_dump())
    ctx.values["spec"] = spec
    result = ctx.get("result")
    if result is not None and result.status == "folded":
        faces = (result.defects.get("folded") or {}).get("faces", [])
        msg = (f"no panels or beams built: the optimized mesh has {len(faces)} folded face(s) "
               f"{list(faces)[:8]} (dented or flipped; no glass can be cut from them); see mesh.obj "
               "and report.json")
        ctx.values["parts"] = None
        ctx.values["cad_skipped"] = msg
        ctx.notes.append(msg)
        return "skipped: folded panels"
    turned = ctx["structure"].report.get("turned_over") or {"ok": True}
    if not turned["ok"]:  # a layer past the focal distance: panels and beams would cross
        from fabricate.offset.turnover import turnover_sentence

        msg = "no panels or beams built: " + turnover_sentence(turned)
        ctx.values["parts"] = None
        ctx.values["cad_skipped"] = msg
        ctx.notes.append(msg)
        return "skipped: offset faces turn over"
    try:
        parts = build_parts(ctx["structure"], spec)
    except (ConfigError, MeshError) as exc:
        if result is None or result.success:
            raise  # the design or the part settings: bad input
        # the optimizer did not reach its target and no parts can be cut from its mesh: write what
        # there is (mesh, layers, report) and end marked as a missed tolerance (exit 3)
        msg = (f"no panels or beams built from the unconverged mesh (optimization {result.status}: "
               f"{result.message}): {exc}")
        ctx.values["parts"] = None
        ctx.values["cad_skipped"] = msg
        ctx.notes.append(msg)
        return f"skipped: optimization {result.status}, parts cannot be built"
    ctx.values["parts"] = parts
    from .cad.parts import unit_id

    counts = {k: len({unit_id(i) for g in parts.of_kind(k) for i in g.ids}) for k in ("panel", "beam", "node")}
    return ", ".join(f"{n} {k}s" for k, n in counts.items())


def count_parts(parts) -> int:
    return len(parts)


# -- structure -----------------------------------------------------------------------
def stage_structure(ctx) -> str:
    """The structural check of the beam frame (``fabricate.structure.run.check_run``) when
    ``structure.check`` is ``report`` or ``enforce``: values ["statics"], ["statics_report"],
    ["structure_measures"]."""
    if ctx.config.structure.check == "off":
        return "off (structure.check: off)"
    from fabricate.structure.run import check_run

    return check_run(ctx)


# -- exports -------------------------------------------------------------------------
EXPORTS = (("step", "model.step", "write_step"), ("stl", "model.stl", "write_stl"),
           ("three_mf", "model.3mf", "write_3mf"), ("dxf", "outlines.dxf", "write_dxf"),
           ("svg", "outlines.svg", "write_svg"), ("flat", "flat.json", "write_flat"),
           ("schedules", "glass_schedule.csv", "write_glass_schedule"),
           ("schedules", "steel_cut_list.csv", "write_steel_cut_list"),
           ("schedules", "node_schedule.csv", "write_node_schedule"),
           ("layout_plan", "layout_plan.dxf", "write_layout_plan"), ("bom", "bom.csv", "write_bom"),
           ("ifc", "model.ifc", "write_ifc"), ("rhino", "model.3dm", "write_3dm"), ("nc1", "nc1", "write_nc1"),
           ("gltf", "parts.glb", "write_parts_gltf"))


def stage_exports(ctx) -> str:
    """The config as run, meshes, layers and the CAD files; then the output check in the mode
    ``outputs.check`` asks for (``fabricate.check_fast.run_check``: full, fast or off; ``auto`` by
    the part count), recorded in ``values["check"]["mode"]``."""
    import yaml

    from optimize.atomic import atomic_open
    from optimize.io import write_mesh

    cfg, out = ctx.config, ctx.workdir
    with atomic_open(out / "config.yaml") as fh:
        fh.write(f"# {cfg.name}: the configuration as run (defaults filled in, paths absolute)\n")
        yaml.safe_dump(cfg.as_dict(), fh, sort_keys=False)
    ctx.files["config.yaml"] = {"what": "the configuration as run"}
    if cfg.outputs.mesh:
        write_mesh(out / "mesh.obj", ctx["mesh"])
        ctx.files["mesh.obj"] = {"what": "the optimized mesh (mm)"}
    structure = ctx["structure"]
    if cfg.outputs.layers:
        for i, d in enumerate(structure.distances):
            name = f"layer_{i}.obj"
            write_mesh(out / name, structure.layer_mesh(i))
            ctx.files[name] = {"what": f"offset layer at {d:g} mm"}
    from fabricate import export

    if ctx.get("parts") is None:  # the CAD stage built nothing (folded panels): meshes only
        ctx.values["check"] = {"pass": None, "mode": "off", "checks": {}, "skipped": ctx.get("cad_skipped")}
        return f"{len(ctx.files)} files (no CAD files: {ctx.get('cad_skipped')})"
    wanted = [(key, fname, fn) for key, fname, fn in EXPORTS if cfg.outputs.wanted(key)]
    for key, fname, fn in wanted:
        ctx.progress.advance("exports", 1, fname)
        try:
            extra = {"rhino": {"structure": structure}, "nc1": {"order": cfg.name or "roof"},
                     "step": {"schema": cfg.outputs.step_schema}}.get(key, {})
            facts = getattr(export, fn)(ctx["parts"], out / fname, **extra)
        except ExportError:
            raise
        except Exception as exc:  # an exporter bug or an OCC failure: exit 4, with the file named
            raise ExportError(f"{fname}: export failed: {type(exc).__name__}: {exc}") from exc
        ctx.files[fname] = dict(facts or {})
        if key == "bom" and ctx.get("statics") is not None:  # the structure's columns on the beam rows
            from fabricate.structure.outputs import add_bom_columns

            ctx.files[fname].update(add_bom_columns(out / fname, ctx["statics"]))
    if cfg.outputs.wanted("cut_files"):  # one nested DXF and SVG per material and thickness
        ctx.progress.advance("exports", 1, "nested cut files")
        ctx.files.update(export.write_cut_files(ctx["parts"], out, cfg.outputs.nesting.model_dump()))
    if cfg.outputs.stl_parts:  # one STL per part (a welding viewer fuses the touching parts of model.stl)
        ctx.progress.advance("exports", 1, "one STL per part")
        ctx.files["stl/"] = export.write_stl_parts(ctx["parts"], out / "stl")
    if not cfg.outputs.bom:  # the checks compare every file with the bill of materials
        ctx.values["check"] = {"pass": None, "mode": "off", "checks": {},
                               "skipped": "bom.csv was not written (outputs.bom: false)"}
        return f"{len(ctx.files)} files, not checked"
    from fabricate.check_fast import run_check

    n_parts = count_parts(ctx["parts"])
    mode = cfg.outputs.check_mode(n_parts)
    ctx.progress.advance("exports", 1, f"checking the files ({mode})")
    check = run_check(out, mode, tol=cfg.tolerances.to_tolerances())
    check["mode_asked"] = cfg.outputs.check
    check["parts"] = n_parts
    ctx.values["check"] = check
    if mode == "off":
        return f"{len(ctx.files)} files, not checked (outputs.check: off)"
    failed = [k for k, v in check.get("checks", {}).items() if isinstance(v, dict) and v.get("pass") is False]
    return f"{len(ctx.files)} files, " + (f"{mode} check FAILED: {', '.join(failed)}" if failed
                                          else f"{mode} check passed")


# -- report ----------------------------------------------------------------------------
def stage_report(ctx) -> str:
    """report.json, pictures, model.glb and report.html (``fabricate.report``)."""
    from fabricate.report import write_report

    try:
        written = write_report(ctx)
    except (ExportError, MeshError, ConfigError):
        raise
    except Exception as exc:
        raise ExportError(f"report: {type(exc).__name__}: {exc}") from exc
    return f"{len(written)} report files"


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
