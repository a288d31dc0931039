"""The output check in the mode a run asks for (``outputs.check``): full, fast or off.

``full`` is :func:`fabricate.check.check_outputs` as it is (the STEP read by
an independent text reader); ``occ`` the same with OpenCASCADE reading the
STEP back (``fabricate check --occ``).  ``fast`` runs the
same checks with ``skip={"step", "ifc_geometry"}`` (the STEP is not read back: OpenCASCADE
reading the STEP back is nearly all of the time on big models: about 10 ms per
part), then puts two light checks, from the files alone, in place of the two
that need the STEP read back:

- ``step``: the STEP text is scanned: complete (``END-ISO-10303-21;``), unit
  mm, one ``MANIFOLD_SOLID_BREP`` per BOM row, product names equal the BOM ids;
- ``dxf``: the independent DXF reader's lint clean, units mm, one CUT outline
  and one ETCH id per panel and beam, each outline's area equal to the BOM's
  (to the BOM's rounding, 1 mm2) instead of the STEP face's.

Every check dict says how it was made; the result carries ``mode``.
``fabricate check OUTDIR`` runs the full check on a finished run.
"""
from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np

from optimize.tolerances import DEFAULT, Tolerances

from .cad.parts import cut_from_sheet

STEP_FILE = "model.step"
DXF_FILE = "outlines.dxf"
BOM_AREA_TOL_MM2 = 0.5
"""The BOM writes areas in m2 with 6 decimals: equal to 1 mm2, half of it either way."""
FAST_NOTE = ("fast check: the STEP text was scanned, OpenCASCADE did not read it back "
             "(outputs.check: fast); `fabricate check OUTDIR` runs the full check")


def run_check(outdir, mode: str, tol: Tolerances = DEFAULT) -> dict:
    """Check a run folder in ``mode`` (``full`` | ``fast`` | ``off``).

    Returns the dict of :func:`fabricate.check.check_outputs` (``pass``,
    ``failed``, ``checks``, ``seconds``) with ``mode`` added; for ``off``,
    ``pass`` is None with the reason in ``skipped``.
    """
    from .check import check_outputs, failure_reasons, light_check, written_files

    out = Path(outdir)
    if mode == "off":
        return {"outdir": str(out), "mode": "off", "pass": None, "failed": [], "checks": {},
                "skipped": "outputs.check: off", "seconds": 0.0}
    if mode in ("full", "occ"):
        return dict(check_outputs(out, tol=tol, step_reader="text" if mode == "full" else "occ"), mode=mode)
    if mode != "fast":
        raise ValueError(f"check mode {mode!r}: expected 'full', 'occ', 'fast' or 'off'")
    t0 = time.perf_counter()
    result = check_outputs(out, tol=tol, skip=frozenset({"step", "ifc_geometry"}))
    from .export.bom import read_bom

    bom = read_bom(out / "bom.csv")
    checks = dict(result["checks"])
    written = written_files(out)
    for name, fname, light in (("step", STEP_FILE, scan_step), ("dxf", DXF_FILE, dxf_against_bom)):
        if (out / fname).exists():
            t1 = time.perf_counter()
            checks[name] = dict(light_check(out / fname, light, bom), seconds=round(time.perf_counter() - t1, 3))
            if checks[name]["pass"] is False:
                checks[name]["why"] = failure_reasons(checks[name])
        elif fname in written:
            checks[name] = {"pass": False, "missing": fname,
                            "why": [f"{fname} is missing: the run wrote it ({written[fname]} bytes)"]}
    failed = [k for k, v in checks.items() if v.get("pass") is False]
    return {"outdir": str(out), "mode": "fast", "pass": not failed, "failed": failed, "checks": checks,
            "note": FAST_NOTE, "seconds": round(time.perf_counter() - t0, 3)}


def scan_step(path, bom: list[dict]) -> dict:
    """The STEP file's text against the BOM: complete, unit mm, solids and product names."""
    data = Path(path).read_bytes()
    names = [m.decode("ascii", "replace") for m in re.findall(rb"PRODUCT\('([^']*)'", data)]
    expected = {r["id"] for r in bom}
    found = set(names)
    missing = sorted(expected - found)
    extra = sorted(found - expected - {"model"})  # the assembly root is not a part
    solids = len(re.findall(rb"MANIFOLD_SOLID_BREP\(", data))
    unit_mm = b"SI_UNIT(.MILLI.,.METRE.)" in data[: 1 << 16].replace(b" ", b"")
    complete = data.rstrip().endswith(b"END-ISO-10303-21;")
    ok = complete and unit_mm and not missing and not extra and solids == len(expected)
    return {"pass": ok, "read_back": False, "complete": complete, "unit_mm": unit_mm, "solids": solids,
            "bom_rows": len(expected), "missing": missing[:20], "unexpected": extra[:20], "note": FAST_NOTE}


def dxf_against_bom(path, bom: list[dict]) -> dict:
    """Flat outlines against the BOM: audit, units, one outline and one id per part, areas."""
    from .export.dxf_text import read_outlines_text as read_outlines
    from .export.verify import outline_areas

    outlines, facts = read_outlines(path)
    area = {r["id"]: float(r["area_m2"]) * 1e6 for r in bom if cut_from_sheet(r["kind"], r.get("member", ""))}
    missing = sorted(set(area) - set(outlines))
    failures, worst, worst_id = [], 0.0, None
    ids = list(outlines)
    got = dict(zip(ids, outline_areas([np.asarray(outlines[i], dtype=float) for i in ids]).tolist()))
    for pid in ids:  # one outline per part
        if pid not in area:
            failures.append({"id": pid, "error": "no BOM row of that id"})
            continue
        a = got[pid]
        err = abs(a - area[pid])
        if err > worst:
            worst, worst_id = err, pid
        if err > BOM_AREA_TOL_MM2 + 1e-9 * area[pid]:
            failures.append({"id": pid, "area_mm2": a, "bom_area_mm2": area[pid]})
    ok = (facts["audit_errors"] == 0 and facts["units"] == 4 and not missing and not failures
          and facts["texts"] >= len(area))
    return {"pass": ok, "against": "bom", "outlines": len(outlines), "expected": len(area),
            "missing": missing[:20], "area_error_mm2_max": worst, "worst": worst_id,
            "tolerance_mm2": BOM_AREA_TOL_MM2, "failures": failures[:20], "failed": len(failures), **facts}
