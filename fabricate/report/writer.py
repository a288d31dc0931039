"""Write the report of a run: pictures, model.glb, a marker for a failed check,
report.json and report.html, into the run's work folder."""
from __future__ import annotations

import logging

import numpy as np

from optimize.mesh import measures as M
from optimize.atomic import atomic_open
from optimize.errors import writing

from .document import build_report, write_report_json
from .glb import glb_bytes
from .html import copy_viewer, highlighted_parts, write_html
from .pictures import picture_defect, picture_history, picture_layers
from .scene import build_scene

log = logging.getLogger(__name__)

MARKERS = {"tolerance_not_reached": "TOLERANCE_NOT_REACHED.txt", "export_failed": "CHECK_FAILED.txt"}


def histories(opt) -> list[tuple[str, list[dict]]]:
    """``[(label, history)]`` of ``opt`` (OptimizeRecord): one per subdivision level, or the single
    optimization's."""
    levels = opt.level_results
    if levels:
        return [(f"level {i + 1}", r.history) for i, r in enumerate(levels) if r is not None]
    result = opt.result
    return [("", result.history)] if result is not None else []


def write_pictures(run) -> dict[str, str]:
    """The PNG pictures of ``run`` (RunRecord); returns ``{file name: caption}``."""
    out, cfg, mesh = run.workdir, run.config, run.optimize.mesh
    tol = cfg.tolerances.to_tolerances()
    name = cfg.name
    pics: dict[str, str] = {}
    picture_defect(mesh, M.planarity(mesh), out / "planarity.png", title=f"{name}: planarity",
                   label="planarity (relative)", tolerance=tol.planarity)
    pics["planarity.png"] = "the design coloured by planarity (log scale)"
    t = mesh.topology
    picture_defect(mesh, M.conical_defect(mesh), out / "conical.png", title=f"{name}: conical defect",
                   label="conical defect (rad)", tolerance=tol.conical, vertices=t.interior_valence4)
    pics["conical.png"] = "conical defect at the interior valence-4 vertices (log scale)"
    s = run.offset.structure
    if s is not None:
        picture_layers(list(s.layers), np.asarray(s.edges), np.asarray(s.beam_quads), out / "layers.png",
                       title=f"{name}: offset layers and beams", distances=tuple(s.distances))
        pics["layers.png"] = "the offset layers with the beams between the first and the last"
    picture_history(histories(run.optimize), out / "history.png", title=f"{name}: optimization history",
                    tolerances={"planarity": tol.planarity, "conical": tol.conical, "circular": tol.circular})
    pics["history.png"] = "max defects against iteration (log scale), tolerances dashed"
    if run.structure.check is not None:  # the structural check's frame pictures
        from fabricate.structure.run import write_pictures as structure_pictures

        pics.update(structure_pictures(run.structure.check, out, name))
    parts = run.parts.parts
    if parts is not None and any(g.kind in ("panel", "beam") and len(g) for g in parts.groups):
        pics.update(shop_pictures(run, parts))
    if parts is not None and parts.of_kind("panel"):  # the glass shapes on the roof (#37 item 3)
        from .classes import classes_picture

        pics.update(classes_picture(run, parts))
    return pics


def shop_pictures(run, parts) -> dict[str, str]:
    """``sheets.png`` (the fullest glass and steel sheet of the nested cut files) and ``layout_plan.png``."""
    from .shop_pictures import picture_plan, picture_sheets, plan_drawing, sheet_drawings

    out, name = run.workdir, run.config.name
    batches = run.exports.cut_batches
    written = batches is not None
    if batches is None:  # cut files not written: the same nesting, drawn only
        from fabricate.export.cutfiles import nest_cut_files

        batches = nest_cut_files(parts, run.config.outputs.nesting.model_dump())
    sheets = sheet_drawings(batches)
    picture_sheets(sheets, out / "sheets.png", title=f"{name}: nested stock sheets")
    files = ", ".join(s["file"] for s in sheets)
    pics = {"sheets.png": (f"the fullest nested sheet of {files}, parts with their ids and the sheet's yield"
                           if written else "the nesting of the cut files (not written: outputs.cut_files off)")}
    picture_plan(plan_drawing(parts), out / "layout_plan.png", title=f"{name}: layout plan")
    pics["layout_plan.png"] = "the layout plan: every glass unit and beam id where it sits on the roof (plan view)"
    return pics


def write_report(run) -> list[str]:
    """Every report file of ``run`` (:class:`fabricate.app.records.RunRecord`, the only input) into its
    work folder; their names."""
    out, cfg, mesh = run.workdir, run.config, run.optimize.mesh
    written: list[str] = []
    own: dict[str, dict] = {}  # facts of the files the report writes itself
    pictures = write_pictures(run) if cfg.outputs.pictures else {}
    written += list(pictures)
    if cfg.outputs.html:
        scene = build_scene(mesh, M.planarity(mesh), tolerance=cfg.tolerances.planarity,
                            structure=run.offset.structure, parts=run.parts.parts,
                            highlight=highlighted_parts(run.exports.check, run.measures))
        glb = glb_bytes(scene, generator=f"conical-fab report of {cfg.name}")
        with writing(out / "model.glb", "3D view's model", needed=len(glb)):
            (out / "model.glb").write_bytes(glb)  # the folder itself is renamed into place atomically
        own["model.glb"] = {"what": "the 3D view's model (glTF binary, metres, y up)", "meshes": len(scene)}
        written += ["model.glb"] + copy_viewer(out, glb)
    outcome = run.outcome
    marker = MARKERS.get(outcome.status)
    if marker:
        why = ("do not meet the tolerances (see report.json, measures)" if outcome.status == "tolerance_not_reached"
               else "failed the output check (see report.json, check)")
        with writing(out / marker, "marker"), atomic_open(out / marker) as fh:
            fh.write(f"{cfg.name}: {outcome.message}\nThe results in this folder were written but {why}; "
                     f"status {outcome.status!r}, exit code {outcome.exit_code}.\n")
        written.append(marker)
    report = build_report(run, pictures, own)
    write_report_json(report, out / "report.json")
    written.append("report.json")
    if cfg.outputs.html:
        write_html(report, pictures, out / "report.html", viewer=True)
        written.append("report.html")
    return written
