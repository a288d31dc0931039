"""The structure stage of a run: check the frame, keep the results, draw the pictures.

``check_run(options, structure, spec)`` runs :func:`fabricate.structure.check.check_structure`
on the offset structure with the part spec and returns the check, report.json's ``structure``,
the run's notes and a one-line result; the application's structure stage
(``fabricate.app.stages.stage_structure``) keeps them in its record, with the measures of
:func:`fabricate.structure.outputs.structure_measures` (enforced for ``structure.check:
enforce``: exit 3).  :func:`write_pictures` draws its pictures for the report.
"""
from __future__ import annotations

import numpy as np

from .check import beam_table, check_structure, report
from .sections import built_section


def check_run(opt, structure, spec, parts=None) -> tuple:
    """The structural check of a run: ``opt`` the config's ``structure`` section, ``structure`` the
    OffsetStructure, ``spec`` the PartSpec the beams were cut with, ``parts`` the Parts (the hubs' weight).

    Returns ``(check, report, notes, line)``: the StructureCheck, report.json's ``structure`` (with
    the beam table and the notes), notes for the run (what the check and the cut list disagree on)
    and a one-line result for the progress bar."""
    chk = check_structure(structure, opt, spec, parts=parts)
    rep = report(chk)
    d0, d1 = structure.beam_span
    built_name = built_section(spec, abs(d1 - d0)).name
    notes = []
    if chk.section.name != built_name:
        notes.append(f"checked section {chk.section.name} (structure.section); the CAD stage cut the beams as "
                     f"{built_name} (parts.beam and the layer span): the cut list's weights are those of the plates")
    over = int((chk.results.utilization > 1.0).sum())
    if over and opt.check == "report":
        notes.append(f"{over} beam(s) exceed utilization 1 (max {chk.max_utilization:.3g}); not enforced "
                     "(structure.check: report)")
    slender = chk.slender()
    if slender.size and opt.check == "report":
        notes.append(f"{slender.size} beam(s) have a class 4 section under their N + M (max c/t over its limit "
                     f"{rep['class_4']['max_ratio']:.3g}); not enforced (structure.check: report)")
    rep["notes"] = notes
    rep["beams"] = beam_table(chk)
    u = rep["utilization"]
    worst = u["worst"][0]["id"] if u["worst"] else "-"
    line = (f"max utilization {u['max']:.3g} ({worst}, {rep['governing_combination']}), deflection "
            f"{rep['deflection']['max_ratio']:.3g} of {rep['deflection']['limit']}")
    return chk, rep, [f"structure: {n}" for n in notes], line


def write_pictures(chk, out, name: str) -> dict[str, str]:
    """The frame of ``chk`` (StructureCheck) coloured by utilization and the deflected shape, into the
    folder ``out`` (the report stage calls this); ``{file name: caption}``."""
    from .pictures import picture_deflection, picture_utilization

    r, fr = chk.results, chk.frame
    pics = {}
    picture_utilization(fr.X, fr.elements, r.utilization, np.asarray(chk.supports),
                        out / "structure_utilization.png", title=f"{name}: steel utilization, max "
                        f"{chk.max_utilization:.3g}")
    pics["structure_utilization.png"] = "the beam frame coloured by utilization (governing ULS combination)"
    _, scale = picture_deflection(fr.X, fr.elements, r.node_displacement, out / "structure_deflection.png",
                                  title=f"{name}: deflected shape", combination=r.governing_sls)
    pics["structure_deflection.png"] = (f"the deflected frame ({r.governing_sls}), displacements exaggerated "
                                        f"x {scale:g}")
    st = chk.stability
    if st is not None and st.buckling is not None and len(st.buckling.alphas):
        b = st.buckling
        picture_deflection(b.X, b.elements, b.modes[0], out / "structure_mode.png",
                           title=f"{name}: first buckling mode, alpha_cr = {b.alpha_cr:.3g}",
                           combination=st.combination, label="mode shape (largest translation 1)", unit="")
        pics["structure_mode.png"] = (f"the first buckling mode of {st.combination} (alpha_cr {b.alpha_cr:.3g}; "
                                      f"{'second-order analysis below 10' if b.alpha_cr < 10 else 'first order: 10 or more'})")
    return pics
