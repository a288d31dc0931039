"""What the structural check adds to a run's outputs: measures (exit code), bom.csv columns,
the report.html section.  Pictures are in :mod:`fabricate.structure.pictures`."""
from __future__ import annotations

import csv
from html import escape
from pathlib import Path

import numpy as np

from optimize.atomic import atomic_open
from optimize.errors import ExportError, write_error

BOM_COLUMNS = ("section", "N_kN", "M_strong_kNm", "M_weak_kNm", "utilization", "combination", "deflection_mm",
               "deflection_limit_mm")
"""Columns appended to the beam rows of bom.csv (empty on panels and nodes): the figures of the beam,
on each of the rows of the plates it is welded from (their ``unit``)."""


def structure_measures(check) -> dict[str, dict]:
    """``{name: entry}`` in the format of :func:`fabricate.report.measures.entry`: utilization
    (limit 1), beam deflection / its limit, node displacement (mm, limit span / n), section class (c/t
    over the class limit, limit 1: above it class 4); enforced when ``structure.check`` is ``enforce``."""
    from fabricate.report.measures import entry

    r, opt = check.results, check.options
    enforced = opt.check == "enforce"
    ids = np.arange(check.frame.n_elements)
    extra = {}
    if check.stability is not None and check.stability.alphas:
        alphas = np.array(list(check.stability.alphas.values()), dtype=float)
        extra["structure_stability"] = entry(1.0 / alphas, 1.0, "ratio", "combination", enforced=enforced,
                                             what="1 / alpha_cr of each ULS combination (linear buckling analysis; "
                                                  "above 1 the frame buckles under it)")
    return extra | {
        "structure_utilization": entry(r.utilization, 1.0, "ratio", "beam", ids=ids, enforced=enforced,
                                       what=f"steel utilization ({opt.grade}, governing ULS combination; "
                                            "cross-section and flexural buckling)"),
        "structure_deflection": entry(check.deflection_ratio(), 1.0, "ratio", "beam", ids=ids, enforced=enforced,
                                      extra={"mm": r.deflection_mm},
                                      what=f"beam deflection / (L/{opt.deflection_limit:g}) (SLS)"),
        "structure_displacement": entry(r.displacement_mm, r.displacement_limit_mm, "mm", "beam", ids=ids,
                                        enforced=enforced, extra={"mm": r.displacement_mm},
                                        what=f"node displacement against span/{opt.deflection_limit:g} = "
                                             f"{r.span_mm:.0f}/{opt.deflection_limit:g} mm (SLS)"),
        "structure_section_class": entry(r.section_class.ratio, 1.0, "ratio", "beam", ids=ids, enforced=enforced,
                                         what="c/t of the beam's most slender plate over its class limit (EN 1993-1-1 "
                                              "Table 5.2 under the beam's N + M, ULS); above 1: class 4, local "
                                              "buckling is not checked"),
    }


def add_bom_columns(path, check) -> dict:
    """Rewrite ``bom.csv`` (atomically) with :data:`BOM_COLUMNS` filled on the beam rows: a beam's figures
    on every row whose ``unit`` is that beam (its own row, or each plate ``B0001.1 ...`` of a welded one)."""
    path = Path(path)
    r, fr = check.results, check.frame
    names = [s.name for s in fr.sections]
    by_id = {}
    for i, pid in enumerate(fr.ids):
        by_id[pid] = (names[fr.section_of[i]], f"{r.N_kN[i]:.3f}", f"{r.M_strong_kNm[i]:.4f}",
                      f"{r.M_weak_kNm[i]:.4f}", f"{r.utilization[i]:.4f}",
                      r.uls[int(r.governing[i])] if r.uls else "", f"{r.deflection_mm[i]:.3f}",
                      f"{r.deflection_limit_mm[i]:.2f}")
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
        if not rows:
            raise ExportError(f"{path}: empty bill of materials, expected a header row")
        head, kind = rows[0], rows[0].index("kind")
        unit = head.index("unit") if "unit" in head else 0
        filled = 0
        with atomic_open(path, "w", encoding="utf-8", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(head + list(BOM_COLUMNS))
            for row in rows[1:]:
                extra = by_id.get(row[unit]) if row[kind] == "beam" else None
                filled += extra is not None
                w.writerow(row + list(extra or ("",) * len(BOM_COLUMNS)))
    except OSError as exc:
        raise write_error(path, "structure columns", exc) from exc
    return {"structure_columns": list(BOM_COLUMNS), "structure_rows": filled}


def _f(v, fmt=".3g") -> str:
    return "" if v is None else format(v, fmt) if isinstance(v, (int, float)) else escape(str(v))


def html_section(rep: dict | None) -> str:
    """The report.html section of ``report.json["structure"]`` (empty string when there is none)."""
    if not rep:
        return ""
    if rep.get("skipped"):
        return f"<h2>Structure</h2><p>{escape(rep['skipped'])}</p>"
    u, d, disp = rep["utilization"], rep["deflection"], rep["displacement"]
    verdict = "passes" if rep["pass"] else "FAILS"
    cls = "pass" if rep["pass"] else "fail"
    rows = "".join(
        f"<tr><td>{escape(w['id'])}</td><td class=num>{w['value']:.3f}</td><td>{escape(w['combination'])}</td>"
        f"<td class=num>{w['N_kN']:.1f}</td><td class=num>{w['M_strong_kNm']:.2f}</td>"
        f"<td class=num>{w['M_weak_kNm']:.2f}</td></tr>" for w in u["worst"])
    drows = "".join(
        f"<tr><td>{escape(w['id'])}</td><td class=num>{w['deflection_mm']:.2f}</td><td class=num>{w['limit_mm']:.1f}"
        f"</td><td class=num>{w['value']:.3f}</td></tr>" for w in d["worst"])
    notes = "".join(f"<li>{escape(n)}</li>" for n in rep.get("notes", []) + class_4_lines(rep.get("class_4")))
    return (f"<h2>Structure</h2><p>The steel frame <span class=\"{cls}\">{verdict}</span> the check "
            f"(structure.check: {escape(rep['check'])}; {escape(rep['engine'])}): max utilization "
            f"{_f(u['max'])} ({escape(str(rep['governing_combination']))}), beam deflection {_f(d['max_ratio'])} of "
            f"{escape(d['limit'])}, node displacement {disp['max_mm']:.1f} mm of {disp['limit_mm']:.0f} mm "
            f"(span {disp['span_mm'] / 1000:.1f} m / {escape(d['limit'].split('/')[-1])}). Section "
            f"{escape(', '.join(rep['sections']))}, {escape(rep['grade'])}, {rep['steel_mass_kg'] / 1000:.1f} t; "
            f"{rep['supports']['count']} {escape(rep['supports']['kind'])} supports, "
            f"{escape(rep['connections'])} joints; equilibrium residual {rep['equilibrium']['max']:.1e}.</p>"
            f"<p><small>{escape(u['method'])}</small></p>"
            "<table><tr><th>beam</th><th>utilization</th><th>combination</th><th>N kN</th>"
            f"<th>M strong kNm</th><th>M weak kNm</th></tr>{rows}</table>"
            "<table><tr><th>beam</th><th>deflection mm</th><th>limit mm</th><th>ratio</th></tr>"
            f"{drows}</table>" + (f"<ul>{notes}</ul>" if notes else ""))


def class_4_lines(c4: dict | None) -> list[str]:
    """The report's lines on class 4 beams (``report.json["structure"]["class_4"]``): how many, the worst."""
    if not c4 or not c4.get("count"):
        return []
    shown = [w for w in c4["worst"] if w["class"] == 4]
    worst_ = "; ".join(f"{w['id']} {w['section']}: {w['part']} c/t {w['c_t']:.1f} > {w['limit']:.1f} "
                       f"(alpha {w['alpha']:.2f}, psi {w['psi']:.2f}; N {w['N_kN']:.1f} kN, "
                       f"M {w['M_top_kNm']:.2f} kNm, {w['combination']})" for w in shown)
    more = c4["count"] - len(shown)
    return [f"{c4['count']} beam(s) with a class 4 section under their N + M (EN 1993-1-1 Table 5.2; local "
            f"buckling is not checked, so they fail): {worst_}" + (f"; and {more} more (report.json "
                                                                   "structure.class_4.beams)" if more > 0 else "")]
