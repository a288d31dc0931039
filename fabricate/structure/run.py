"""The structure stage of a run: check the frame, keep the results, draw the pictures.

``check_run(ctx)`` (``ctx``: :class:`fabricate.pipeline.RunContext`) reads the offset structure
and the part spec, runs :func:`fabricate.structure.check.check_structure`, and leaves in
``ctx.values``: ``statics`` (the StructureCheck), ``statics_report`` (report.json's
``structure``) and ``structure_measures`` (measures with the check's pass/fail, enforced for
``structure.check: enforce``: exit 3).  :func:`write_pictures` draws its pictures for the report.
"""
from __future__ import annotations

import numpy as np

from .check import beam_table, check_structure, report
from .outputs import structure_measures
from .sections import built_section


def check_run(ctx) -> str:
    cfg = ctx.config
    opt = cfg.structure
    if ctx.get("parts") is None and ctx.get("cad_skipped"):
        msg = f"structure check skipped: {ctx.get('cad_skipped')}"
        ctx.values["statics_report"] = {"check": opt.check, "skipped": msg}
        ctx.notes.append(msg)
        return "skipped: no parts"
    spec = ctx["spec"]
    chk = check_structure(ctx["structure"], opt, spec)
    rep = report(chk)
    d0, d1 = ctx["structure"].beam_span
    built = built_section(spec, abs(d1 - d0)).name
    notes = []
    if chk.section.name != built:
        notes.append(f"checked section {chk.section.name} (structure.section); the CAD stage cut the beams as "
                     f"{built} (parts.beam and the layer span): the cut list's weights are those of the plates")
    over = int((chk.results.utilization > 1.0).sum())
    if over and opt.check == "report":
        notes.append(f"{over} beam(s) exceed utilization 1 (max {chk.max_utilization:.3g}); not enforced "
                     "(structure.check: report)")
    rep["notes"] = notes
    rep["beams"] = beam_table(chk)
    ctx.values["statics"] = chk
    ctx.values["statics_report"] = rep
    ctx.values["structure_measures"] = structure_measures(chk)
    ctx.notes.extend(f"structure: {n}" for n in notes)
    u = rep["utilization"]
    worst = u["worst"][0]["id"] if u["worst"] else "-"
    return (f"max utilization {u['max']:.3g} ({worst}, {rep['governing_combination']}), deflection "
            f"{rep['deflection']['max_ratio']:.3g} of {rep['deflection']['limit']}")


def write_pictures(ctx) -> dict[str, str]:
    """The frame coloured by utilization and the deflected shape (the report stage calls this);
    ``{file name: caption}``."""
    from .pictures import picture_deflection, picture_utilization

    chk = ctx["statics"]
    out, name, r, fr = ctx.workdir, ctx.config.name, chk.results, chk.frame
    pics = {}
    picture_utilization(fr.X, fr.elements, r.utilization, np.asarray(chk.supports),
                        out / "structure_utilization.png", title=f"{name}: steel utilization, max "
                        f"{chk.max_utilization:.3g}")
    pics["structure_utilization.png"] = "the beam frame coloured by utilization (governing ULS combination)"
    _, scale = picture_deflection(fr.X, fr.elements, r.node_displacement, out / "structure_deflection.png",
                                  title=f"{name}: deflected shape", combination=r.governing_sls)
    pics["structure_deflection.png"] = (f"the deflected frame ({r.governing_sls}), displacements exaggerated "
                                        f"x {scale:g}")
    return pics
