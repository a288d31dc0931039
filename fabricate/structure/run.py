"""The structure stage of a run: check the frame, keep the results, draw the pictures.

``check_run(cfg, offset, parts)`` reads the offset structure and the part spec from their
records, runs :func:`fabricate.structure.check.check_structure`, and returns the
:class:`fabricate.records.StructureRecord`: ``check`` (the StructureCheck), ``report``
(report.json's ``structure``) and ``measures`` (with the check's pass/fail, enforced for
``structure.check: enforce``: exit 3).  :func:`write_pictures` draws its pictures for the report.
"""
from __future__ import annotations

import numpy as np

from .check import beam_table, check_structure, report
from .outputs import structure_measures


def check_run(cfg, off, built):
    """The :class:`fabricate.records.StructureRecord` of the run: ``off`` (OffsetRecord) and ``built``
    (PartsRecord) give the beam network and the part spec."""
    from fabricate.records import StructureRecord, frozen

    opt = cfg.structure
    if built.parts is None and built.skipped:
        msg = f"structure check skipped: {built.skipped}"
        return StructureRecord(report=frozen({"check": opt.check, "skipped": msg}), notes=(msg,),
                               line="skipped: no parts")
    spec = built.spec
    chk = check_structure(off.structure, opt, spec)
    rep = report(chk)
    d0, d1 = off.structure.beam_span
    built_name = f"plate {spec.beam_width:g}x{abs(d1 - d0):g}"
    notes = []
    if chk.section.name != built_name:
        notes.append(f"checked section {chk.section.name} (structure.section); the CAD stage cut the beams as "
                     f"{built_name} (parts.beam_width x the layer span): the cut list's weights are those of the plates")
    over = int((chk.results.utilization > 1.0).sum())
    if over and opt.check == "report":
        notes.append(f"{over} beam(s) exceed utilization 1 (max {chk.max_utilization:.3g}); not enforced "
                     "(structure.check: report)")
    rep["notes"] = notes
    rep["beams"] = beam_table(chk)
    u = rep["utilization"]
    worst = u["worst"][0]["id"] if u["worst"] else "-"
    line = (f"max utilization {u['max']:.3g} ({worst}, {rep['governing_combination']}), deflection "
            f"{rep['deflection']['max_ratio']:.3g} of {rep['deflection']['limit']}")
    return StructureRecord(check=chk, report=frozen(rep), measures=frozen(structure_measures(chk)),
                           notes=tuple(f"structure: {n}" for n in notes), line=line)


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
    return pics
