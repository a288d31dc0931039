"""``fabricate check`` of the nested cut files, ``cut_<material>_<t>mm.dxf``: what the shop cuts from.

Each cut file is read by the independent DXF text reader (:mod:`fabricate.export.dxf_text`) and held to:

- the file itself: no lint (group codes, handles, closed outlines), units mm, a frame on layer
  ``SHEET`` and a label for every stock sheet (the label states its margin and kerf);
- its parts: every CUT outline is a bill-of-materials row of the file's material and thickness
  (``glass`` / ``steel``, the row's ``thickness_mm``), cut from sheet, in no other cut file, and has
  the shape of that part's outline in ``outlines.dxf`` (which the DXF check holds to ``flat.json``,
  and so to the STEP solid) up to a move and a quarter turn, within ``tol.file_edge_mm``;
- the sheets: every outline lies on one sheet, its margin clear, and the boxes around two outlines
  on a sheet stay at least the kerf apart (the nesting places each part in its stock rectangle, so
  boxes apart means parts apart);
- nothing left out: every material and thickness has its cut file, and every row of it is in it,
  unless its stock rectangle with the margins does not fit the sheet (a part larger than the sheet
  is listed, not nested: :func:`fabricate.export.cutfiles.nest_cut_files`; a file of no sheet at all,
  every part too large, states no sheet size to hold its rows to).
"""
from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np

from optimize.errors import ExportError
from optimize.tolerances import DEFAULT, Tolerances

from .cad.parts import cut_from_sheet

CUT_FILE = re.compile(r"cut_(glass|steel)_(\d+(?:\.\d+)?)mm\.dxf")
LABEL = re.compile(r"(\d+(?:\.\d+)?) x (\d+(?:\.\d+)?) mm, margin (\d+(?:\.\d+)?) mm, kerf (\d+(?:\.\d+)?) mm")
SLACK = 1e-6
"""mm: how far a coordinate may stray past a margin or a kerf (the files carry 17 digits)."""
FIT = 0.01
"""mm: how close to the sheet a row's stock rectangle (3 decimals in the BOM) may come and still be
taken as too large for it."""
CHUNK = 512
"""Rows of a sheet's box pairs compared at a time."""


def batches(bom) -> dict[tuple[str, float], dict]:
    """``{(material, thickness): {id: row}}`` of the rows cut from sheet, glass and steel."""
    out: dict[tuple[str, float], dict] = {}
    for r in bom:
        if cut_from_sheet(r["kind"], r.get("member", "")) and r.get("material") in ("glass", "steel"):
            out.setdefault((r["material"], round(float(r["thickness_mm"]), 3)), {})[r["id"]] = r
    return out


def check_cut_files(folder, bom, strip: dict[str, np.ndarray], written: dict,
                    tol: Tolerances = DEFAULT) -> dict:
    """The checks of the module docstring on the cut files in ``folder``; ``strip``: ``outlines.dxf``'s
    outlines as the DXF check read them; ``written``: the files the run lists (a cut file it wrote
    that is gone fails)."""
    from .export.dxf_text import read_outlines_text
    from .export.verify import not_regular

    t0 = time.perf_counter()
    folder = Path(folder)
    files = sorted(p for p in folder.glob("cut_*mm.dxf") if CUT_FILE.fullmatch(p.name))
    gone = sorted(set(n for n in written if CUT_FILE.fullmatch(n)) - {p.name for p in files})
    if not files and not gone:
        return {"pass": None, "skipped": "no cut files were written"}
    rows = batches(bom)
    failures: list[dict] = [{"file": n, "error": "the run wrote it; it is missing"} for n in gone]
    seen: dict[str, str] = {}
    sheets = outlines_n = 0
    covered: dict[tuple[str, float], tuple[float, float, float] | None] = {}
    for path in files:
        m = CUT_FILE.fullmatch(path.name)
        key = (m.group(1), round(float(m.group(2)), 3))
        covered[key] = None                                  # there; its sheet size from its labels
        if (what := not_regular(path)) is not None:                 # a pipe or device may never end
            failures.append({"file": path.name, "error": f"{what}, not a file; refused unopened"})
            continue
        try:
            outlines, facts = read_outlines_text(path, sheets=True)
        except ExportError as exc:
            failures.append({"file": path.name, "error": str(exc)})
            continue
        outlines_n += len(outlines)
        sheets += len(facts["sheets"])
        bad = _file_errors(facts, len(outlines))
        failures += [{"file": path.name, "error": e} for e in bad]
        labels = [LABEL.search(t) for t in facts["sheet_labels"]]
        if bad or not labels or not all(labels):
            if labels and not bad:
                failures.append({"file": path.name, "error": "a sheet label without its size, margin and kerf"})
            continue                                         # no sheets (every part too large): nothing nested
        W, H, margin, kerf = (float(x) for x in labels[0].groups())
        covered[key] = (W, H, margin)
        mine = rows.get(key, {})
        for pid in outlines:
            if pid not in mine:
                failures.append({"file": path.name, "id": pid,
                                 "error": f"not a {key[0]} part {key[1]:g} mm thick in the bill of materials"})
            elif pid in seen:
                failures.append({"file": path.name, "id": pid, "error": f"also in {seen[pid]}"})
            seen.setdefault(pid, path.name)
        failures += [dict(f, file=path.name) for f in _shape_errors(outlines, strip, tol.file_edge_mm)]
        failures += [dict(f, file=path.name) for f in _sheet_errors(outlines, facts["sheets"], margin, kerf)]
    for key, mine in rows.items():
        if key not in covered:
            if files:   # the writer writes one file per material and thickness, empty when nothing fits
                failures.append({"file": f"cut_{key[0]}_{key[1]:g}mm.dxf", "error": f"no cut file for the "
                                 f"{len(mine)} {key[0]} parts {key[1]:g} mm thick"})
            continue
        if covered[key] is None:   # a file without sheets: its parts' sizes against the sheet are not in it
            continue
        W, H, margin = covered[key]
        for pid, r in mine.items():
            w, h = float(r["rect_w_mm"]) + 2 * margin, float(r["rect_h_mm"]) + 2 * margin
            fits = (w <= W - FIT and h <= H - FIT) or (h <= W - FIT and w <= H - FIT)
            if pid not in seen and fits:
                failures.append({"id": pid, "error": f"in no cut file; its stock rectangle fits the "
                                                    f"{key[0]} {key[1]:g} mm sheet"})
    return {"pass": not failures, "files": len(files), "outlines": outlines_n, "sheets": sheets,
            "failed": len(failures), "failures": failures[:20], "seconds": round(time.perf_counter() - t0, 3)}


def _file_errors(facts: dict, outlines: int) -> list[str]:
    out = list(facts["lint"])
    if facts["units"] != 4:
        out.append(f"$INSUNITS {facts['units']}, expected 4 (mm)")
    if (outlines and not len(facts["sheets"])) or len(facts["sheet_labels"]) != len(facts["sheets"]):
        out.append(f"{len(facts['sheets'])} sheet frames and {len(facts['sheet_labels'])} sheet labels for "
                   f"{outlines} parts: expected one label per frame, one frame or more when there are parts")
    return out


def _by_corners(outlines: dict) -> list[tuple[list[str], np.ndarray]]:
    """The outlines stacked by their number of corners: ``[(ids, (n, k, 2))]``."""
    by_k: dict[int, list[str]] = {}
    for pid, Q in outlines.items():
        by_k.setdefault(len(Q), []).append(pid)
    return [(ids, np.stack([outlines[p] for p in ids])) for ids in by_k.values()]


def _turns(Q: np.ndarray) -> list[np.ndarray]:
    """``Q (n, k, 2)`` moved to the origin as it is and turned a quarter either way."""
    out = []
    for R in (Q, np.stack([-Q[..., 1], Q[..., 0]], axis=-1), np.stack([Q[..., 1], -Q[..., 0]], axis=-1)):
        out.append(R - R.min(axis=1, keepdims=True))
    return out


def _shape_errors(outlines: dict, strip: dict, tol_mm: float) -> list[dict]:
    """Outlines whose shape is not their ``outlines.dxf`` outline's (moved, turned a quarter or not)."""
    out = [{"id": pid, "error": f"{len(Q)} corners, {len(strip[pid])} in outlines.dxf"}
           for pid, Q in outlines.items() if pid in strip and len(strip[pid]) != len(Q)]
    for ids, A in _by_corners({p: Q for p, Q in outlines.items() if p in strip and len(strip[p]) == len(Q)}):
        B = np.stack([strip[p] for p in ids])
        A0 = A - A.min(axis=1, keepdims=True)
        err = np.min([np.abs(A0 - T).max(axis=(1, 2)) for T in _turns(B)], axis=0)
        for i in np.flatnonzero(~(err <= tol_mm)):                      # NaN fails
            out.append({"id": ids[i], "error": f"not the shape of its outline in outlines.dxf: "
                                               f"{err[i]:.3g} mm off"})
    return out


def _sheet_errors(outlines: dict, frames: np.ndarray, margin: float, kerf: float) -> list[dict]:
    """Outlines off their sheet or inside its margin, and pairs on a sheet closer than the kerf."""
    if not outlines:
        return []
    ids, boxes = [], []
    for group, A in _by_corners(outlines):
        ids += group
        boxes.append(np.concatenate([A.min(axis=1), A.max(axis=1)], axis=1))
    box = np.concatenate(boxes)                                                                    # (n, 4)
    lo, hi = frames.min(axis=1), frames.max(axis=1)                                                # (s, 2)
    inside = ((box[:, None, :2] >= lo[None] + margin - SLACK).all(axis=2)
              & (box[:, None, 2:] <= hi[None] - margin + SLACK).all(axis=2))                       # (n, s)
    out = [{"id": ids[i], "error": f"on no sheet with its {margin:g} mm margin clear"}
           for i in np.flatnonzero(inside.sum(axis=1) != 1)]
    sheet = np.where(inside.sum(axis=1) == 1, inside.argmax(axis=1), -1)
    for s in range(len(frames)):
        idx = np.flatnonzero(sheet == s)
        b = box[idx]
        for a in range(0, len(b), CHUNK):
            c = b[a:a + CHUNK]
            gap = np.maximum(np.maximum(c[:, None, 0] - b[None, :, 2], b[None, :, 0] - c[:, None, 2]),
                             np.maximum(c[:, None, 1] - b[None, :, 3], b[None, :, 1] - c[:, None, 3]))
            gap[np.arange(len(c)), a + np.arange(len(c))] = np.inf
            for i, j in zip(*np.nonzero(gap < kerf - SLACK)):
                if a + i < j:
                    out.append({"id": ids[idx[a + i]], "error": f"{gap[i, j]:.3g} mm from {ids[idx[j]]} on sheet "
                                                                f"{s + 1}, less than the {kerf:g} mm kerf"})
    return out
