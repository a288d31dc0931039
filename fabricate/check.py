"""``check_outputs``: re-validate a finished run from its files alone.

The bill of materials is the reference (ids, kinds, analytic volumes,
neighbours).  Each file is read back by an independent reader and compared
with it:

- ``step``: an independent reader of the STEP text (:mod:`fabricate.export.step_text`,
  neither the writer's code nor OpenCASCADE) reads ``model.step``; part count
  and names equal the BOM's; every solid is a closed, consistently oriented
  planar polyhedron (each edge used twice in opposite directions, Euler
  characteristic 2, loops closed, simple and counter-clockwise about their
  outward plane normals, vertices on their planes and lines within the
  file's declared accuracy); its volume equals the analytic volume to
  ``1e-6`` relative; the file's unit is mm; every solid has a colour, one
  per kind, different kinds different.  With ``step_reader="occ"``
  (``fabricate check --occ``) OpenCASCADE reads it back instead and every
  solid passes ``BRepCheck_Analyzer`` (about 10 ms a part), and ezdxf
  audits the DXF.
- ``3mf``: one object per BOM row, same names; manifold3d (double precision)
  accepts each as a closed 2-manifold; volumes to ``1e-6``.
- ``stl``: split into parts with the 3MF's triangle counts, welded per part;
  manifold3d status ok, one component per part, genus ``1 - parts``; volume
  within the float32 bound ``4 eps32 max|x| area``.
- ``intersections``: no two parts overlap (3MF meshes; bounding-box pairs,
  a separating face plane or a manifold3d intersection volume below
  ``cad_linear_mm x`` the smaller surface area).
- ``bearing``: every panel touches each beam listed as its neighbour
  (manifold3d gap below ``cad_linear_mm``).
- ``flat``: every panel, beam and hub cap plate rebuilt from ``flat.json`` alone (outline,
  bevels, thickness, transform) has the volume and, within 0.01 mm, the
  corners of its STEP solid (3MF mesh in the fast check).
- ``dxf``: read by an independent reader (:mod:`fabricate.export.dxf_text`: lint
  of codes, sections, handles, closed outlines; ``--occ``: ezdxf loads and
  audits the whole file), units mm, one CUT outline (id in XDATA) and
  one ETCH id per part cut from sheet (panel, beam, hub cap), and each outline has the area
  (``tol.file_area``, ``1e-9`` relative) and the edge lengths (``tol.file_edge_mm``, ``1e-6`` mm) of
  the flat data's outline with the same id, a BOM row's (without ``flat.json``: its area
  against the BOM's).
- ``cut``: the nested cut files ``cut_<material>_<t>mm.dxf`` (:mod:`fabricate.check_cut`): every part
  cut from sheet once, in the file of its material and thickness, of the shape of its
  ``outlines.dxf`` outline (moved, turned a quarter or not), on one sheet with the margin clear and
  the kerf kept to the others; left out only when too large for the sheet.
- ``svg``: parses, one group per part cut from sheet.
- ``welds``: ``weld_schedule.csv`` against the BOM (:func:`fabricate.export.welds.check_weld_schedule`:
  every part it names exists, a joint joins parts of its assembly, every welded beam's plates are
  joined, the totals add up).
- ``bars``: ``bar_cutting.csv`` against ``steel_cut_list.csv`` (:func:`fabricate.export.bars.check_bar_plan`:
  every beam and hub tube on exactly one bar, with its length, section and grade and the cut list's
  ``bar``; every bar's pieces, kerfs and end trims within its stock length).
- ``ifc``, ``3dm``, ``nc1``: the exchange files (:mod:`fabricate.export.exchange_check`): one
  element / object / file per BOM row with the same id; IFC schema-valid with the volume of
  every element's face set, as ifcopenshell reads it, equal to the BOM's (with ``--occ``: from
  ifcopenshell's geometry kernel; not in the fast check: ``skip`` ``ifc_geometry``).

- ``glass_order``: ``glass_order.csv`` and its drawings held to the units of ``flat.json``
  (:func:`fabricate.export.check_glass_order.check_glass_order_files`): every unit in exactly one
  position, each within its position's tolerance of the position's DXF, blanks that hold every ply.

- ``files``: every file the run lists as written (its marker :data:`fabricate.app.runfolder.MARKER`,
  written last, else ``report.json``'s ``files``) is there, a regular file, of the size the run wrote;
  a marker or ``report.json`` that does not read fails.  Without either (the check inside a run, files
  written by the library) the row is left out.

A check whose file was not written is reported with ``pass: None`` and the
reason, never silently left out; a file the run wrote (listed by its marker or
``report.json``) that is gone fails, ``missing``.  A file that is not a regular file (a named pipe,
a folder, a device) is refused unopened (it might never end): its check fails.  Every failed check
carries ``why``: the plain reasons, from its figures.
"""
from __future__ import annotations

import logging
import os
import stat
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from optimize.errors import ExportError
from optimize.tolerances import DEFAULT, Tolerances

from .cad.parts import cut_from_sheet
from .check_cut import check_cut_files
from .check_heap import heap_reuse
from .check_mesh import check_3mf as _check_3mf
from .check_mesh import check_stl as _check_stl
from .export.verify import not_regular

log = logging.getLogger(__name__)
FILES = {"bom": "bom.csv", "step": "model.step", "stl": "model.stl", "3mf": "model.3mf",
         "dxf": "outlines.dxf", "svg": "outlines.svg", "flat": "flat.json", "ifc": "model.ifc", "3dm": "model.3dm",
         "nc1": "nc1", "welds": "weld_schedule.csv", "glass_order": "glass_order.csv",
         "bars": "bar_cutting.csv"}
REPORT = "report.json"


def check_outputs(outdir, tol: Tolerances = DEFAULT, *, skip: frozenset[str] = frozenset(),
                  step_reader: str = "text") -> dict:
    """Run every check on ``outdir`` (see :func:`_check_outputs`), big temporaries reused (:func:`heap_reuse`)."""
    with heap_reuse():
        return _check_outputs(outdir, tol, skip=skip, step_reader=step_reader)


def _check_outputs(outdir, tol: Tolerances = DEFAULT, *, skip: frozenset[str] = frozenset(),
                   step_reader: str = "text", only: frozenset[str] | None = None) -> dict:
    """Run every check on ``outdir``; returns ``{"outdir", "pass", "checks": {name: {...}}, "seconds"}``.

    ``pass`` is False when any check failed (``pass: False``); skipped checks
    (file not written) carry ``pass: None`` and ``skipped``.  Raises
    ExportError only when the folder or the bill of materials is unusable.
    ``skip`` names files (keys of ``FILES``, e.g. ``{"step"}``; ``ifc_geometry``: the IFC without
    its schema validation and volumes) not to read:
    their checks, and the checks that need them, carry ``pass: None``.
    ``step_reader``: ``"text"`` (default: :mod:`fabricate.export.step_text`, an
    independent parser of the planar B-rep, as fast as the export) or ``"occ"``
    (OpenCASCADE reads the file back: BRepCheck per solid, about 10 ms a part).
    A big STEP file is read, with the checks that need it, in a child process while this one
    runs the others (:mod:`fabricate.check_lanes`); ``only``: run just these checks, here.
    """
    if step_reader not in ("text", "occ"):
        raise ValueError(f"step_reader {step_reader!r}: expected 'text' or 'occ'")
    from . import check_lanes
    from .export import exchange_check
    from .export.bom import read_bom
    from .export.check_glass_order import check_glass_order_files
    from .export.bars import check_bar_plan
    from .export.welds import check_weld_schedule

    t0 = time.perf_counter()
    out = Path(outdir)
    if not out.is_dir():
        raise ExportError(f"{out}: not a folder; expected the output folder of a run")
    paths = {k: out / v for k, v in FILES.items()}
    if not paths["bom"].exists():
        raise ExportError(f"{paths['bom']}: missing; the checks compare every file with the bill of materials")
    if (what := not_regular(paths["bom"])) is not None:
        raise ExportError(f"{paths['bom']}: {what}, not a file; the checks compare every file with the bill "
                          "of materials")
    bom = read_bom(paths["bom"])
    listing = run_listing(out)
    written = listing.files
    checks: dict[str, dict] = {"bom": _check_bom(bom)}
    if only is None and listing.sources + listing.problems:
        checks["files"] = _check_files(out, listing)
    read: dict[str, object] = {}  # what one check read and the next ones use: STEP solids, 3MF meshes
    table = (
        ("step", "step", None, lambda: (_check_step if step_reader == "occ" else _check_step_text)(
            paths["step"], bom, tol)),
        ("3mf", "3mf", None, lambda: _check_3mf(paths["3mf"], bom, tol)),
        ("stl", "stl", "3mf", lambda: (_check_stl(paths["stl"], bom, read["3mf"]), None)),
        ("intersections", "3mf", "3mf", lambda: (_check_intersections(read["3mf"], tol), None)),
        ("bearing", "3mf", "3mf", lambda: (_check_bearing(read["3mf"], bom, tol), None)),
        ("flat", "flat", None, lambda: (_check_flat(paths["flat"], bom, read), None)),
        ("dxf", "dxf", None, lambda: _check_dxf_keep(paths["dxf"], bom, _readable(paths["flat"]),
                                                     None if step_reader == "occ" else "text", tol)),
        ("cut", "dxf", "dxf", lambda: (check_cut_files(out, bom, read["dxf"], written, tol), None)),
        ("svg", "svg", None, lambda: (_check_svg(paths["svg"], bom), None)),
        ("ifc", "ifc", None, lambda: (exchange_check.check_ifc(paths["ifc"], bom,
                                                                 full="ifc_geometry" not in skip,
                                                                 kernel=step_reader == "occ", tol=tol), None)),
        ("3dm", "3dm", None, lambda: (exchange_check.check_3dm(paths["3dm"], bom), None)),
        ("nc1", "nc1", None, lambda: (exchange_check.check_nc1(paths["nc1"], bom), None)),
        ("welds", "welds", None, lambda: (check_weld_schedule(paths["welds"], bom), None)),
        ("glass_order", "glass_order", None, lambda: (check_glass_order_files(out, _readable(paths["flat"])), None)),
        ("bars", "bars", None, lambda: (check_bar_plan(out), None)))

    def run_checks(names) -> None:
        for name, key, needs, run in table:
            if name in names:
                checks[name] = _one_check(name, key, needs, run, paths, skip, written, read)

    groups = [] if only is not None else check_lanes.lanes_for(paths, skip, step_reader)
    children: list = []
    try:
        for names in groups:
            children.append((names, check_lanes.start(out, names, skip, tol)))
        elsewhere = frozenset().union(*[names for names, child in children if child is not None])
        run_checks(only if only is not None else {t[0] for t in table} - elsewhere)
        for names, child in children:
            theirs = None if child is None else check_lanes.collect(child)
            if theirs is None:
                run_checks(names)
                continue
            checks.update(theirs)
            if "error" in theirs.get("step", {}):   # no solids read: the flat data against the 3MF, here
                run_checks({"flat"})
    finally:
        for _, child in children:
            check_lanes.stop(child)
    checks = {k: checks[k] for k in ["bom", "files"] + [t[0] for t in table] if k in checks}
    failed = [k for k, v in checks.items() if v.get("pass") is False]
    return {"outdir": str(out), "pass": not failed, "failed": failed, "checks": checks,
            "seconds": round(time.perf_counter() - t0, 3)}


def _one_check(name, key, needs, run, paths, skip, written, read) -> dict:
    """One check's result (``read[name]``: what it read, for the checks after it)."""
    t1 = time.perf_counter()
    if key in skip:
        return {"pass": None, "skipped": f"{FILES[key]} not read (skip)"}
    if not paths[key].exists():
        inside = sum(n.startswith(f"{FILES[key]}/") for n in written) if key in FOLDERS else 0
        if FILES[key] in written or inside:
            size = f"{inside} files" if inside else _bytes(written[FILES[key]])
            return {"pass": False, "missing": FILES[key],
                    "why": [f"{FILES[key]} is missing: the run wrote it ({size})"]}
        return {"pass": None, "skipped": f"{FILES[key]} was not written"}
    if (refused := _refused(paths[key], key in FOLDERS)) is not None:
        return {"pass": False, "error": refused}
    if needs and read.get(needs) is None:
        return {"pass": None, "skipped": f"needs a readable {FILES[needs]}"}
    try:
        result, read[name] = run()
    except ExportError as exc:
        result = {"pass": False, "error": str(exc)}
    result["seconds"] = round(time.perf_counter() - t1, 3)
    if result.get("pass") is False:
        result.setdefault("why", failure_reasons(result))
    log.info("check %s: %s", name, {True: "ok", False: "FAILED"}.get(result.get("pass"), "skipped"))
    return result


FOLDERS = frozenset({"nc1"})
"""Keys of :data:`FILES` that name a folder of files (one NC1 file per beam)."""


def _refused(path: Path, folder: bool = False) -> str | None:
    """Why the check does not open ``path`` (a file, or with ``folder`` a folder of files): not a
    regular file (or folder), or a folder holding something that is not a regular file."""
    what = not_regular(path)
    if not folder:
        return None if what is None else f"{path.name}: {what}, not a file; refused unopened"
    if what != "a folder":
        return f"{path.name}: {what or 'a file'}, not a folder of files"
    try:
        inside = sorted(os.scandir(path), key=lambda e: e.name)
    except OSError as exc:
        return f"{path.name}: the folder cannot be listed ({exc.strerror or exc})"
    odd = [f"{path.name}/{e.name} ({w})" for e in inside
           if e.name.endswith(f".{path.name}") and (w := not_regular(e.path)) is not None]
    return (f"{', '.join(odd[:5])}{', ...' if len(odd) > 5 else ''}: not a file; refused unopened"
            if odd else None)


def light_check(path: Path, check, *args) -> dict:
    """``check(path, *args)`` (a check's dict), or its failure when ``path`` is not a regular file
    (refused unopened) or does not read (:class:`ExportError`): the fast check's light rows."""
    if (refused := _refused(path)) is not None:
        return {"pass": False, "error": refused}
    try:
        return check(path, *args)
    except ExportError as exc:
        return {"pass": False, "error": str(exc)}


def _readable(path: Path) -> Path | None:
    """``path`` when it is a regular file, else None (what is not read as the file is not there)."""
    return path if path.exists() and not_regular(path) is None else None


def _bytes(n) -> str:
    return f"{n} bytes" if isinstance(n, int) else "its size not listed"


@dataclass(frozen=True)
class Listing:
    """The files a run says it wrote: ``files`` ``{relative path: bytes or None}`` (the marker's, and
    ``report.json``'s that the marker does not list), ``sources`` (the lists read) and ``problems`` (a
    marker or report that is there and does not read: the folder is not as the run left it)."""

    files: dict[str, int | None]
    sources: list[str]
    problems: list[str]


def run_listing(outdir: Path) -> Listing:
    """The :class:`Listing` of ``outdir``: its marker (:func:`fabricate.app.runfolder.read_marker`,
    written last: every file but itself) and ``report.json``'s ``files``; neither is opened unless it
    is a regular file."""
    from optimize import jsontext
    from optimize.atomic import PART_OWNER

    from .app.runfolder import MARKER, read_marker

    files: dict[str, int | None] = {}
    sources: list[str] = []
    problems: list[str] = []
    path = outdir / MARKER
    if os.path.lexists(path):
        what = not_regular(path)
        marker = read_marker(outdir) if what is None else None
        listed = marker.get("files") if marker is not None else None
        if isinstance(listed, dict):
            sources.append(MARKER)
            files.update((str(k), v[0] if isinstance(v, list) and v and type(v[0]) is int else None)
                         for k, v in listed.items())
        else:
            problems.append(f"{MARKER}: {what + ', not a file' if what else 'not a readable run marker'}; the "
                            "list of the files the run wrote is lost")
    path = outdir / REPORT
    if os.path.lexists(path):
        what = not_regular(path)
        try:
            if what is not None:
                raise ValueError(f"{what}, not a file")
            report = jsontext.loads(path.read_text(encoding="utf-8"))
            listed = report.get("files") if isinstance(report, dict) else None
            if not isinstance(listed, dict):
                raise ValueError("no 'files' object")
        except (OSError, ValueError) as exc:
            problems.append(f"{REPORT}: {getattr(exc, 'strerror', None) or exc}; expected the run's report")
        else:
            sources.append(REPORT)
            for k, v in listed.items():   # the temporary folder's owner record is removed when it is published
                if str(k) != PART_OWNER and str(k) not in files:
                    n = v.get("bytes") if isinstance(v, dict) else None
                    files[str(k)] = n if type(n) is int else None
    return Listing(files, sources, problems)


def written_files(outdir: Path) -> dict[str, int | None]:
    """``{file: bytes}`` the run says it wrote (:func:`run_listing`: its marker and ``report.json``);
    empty without either (the check inside a run, or exports written by the library): then a file not
    there was not written."""
    return run_listing(Path(outdir)).files


def _check_files(outdir: Path, listing: Listing) -> dict:
    """The ``files`` row: every listed file there, a regular file, of the size the run wrote."""
    missing, odd, resized = [], [], []
    for name, size in listing.files.items():
        path = outdir / name
        try:
            st = os.stat(path)
        except (OSError, ValueError):
            missing.append(name)
            continue
        if not stat.S_ISREG(st.st_mode):
            odd.append(f"{name} ({not_regular(path)})")
        elif size is not None and st.st_size != size:
            resized.append(f"{name}: {st.st_size} bytes, the run wrote {size}")
    why = list(listing.problems)
    for items, what in ((missing, "missing (the run wrote them)"), (odd, "not a file (refused unopened)"),
                        (resized, "not of the size the run wrote")):
        if items:
            why.append(f"{len(items)} {what}: {', '.join(items[:5])}{', ...' if len(items) > 5 else ''}")
    out = {"pass": not why, "listed": len(listing.files), "listed_by": " and ".join(listing.sources) or None,
           "missing": missing[:20], "not_files": odd[:20], "resized": resized[:20]}
    if why:
        out["why"] = why
    return out


REASONS = {"missing": "missing from the file", "unexpected": "not in the BOM", "invalid": "invalid solids",
           "volume_failures": "volume off the BOM's", "not_manifold": "not closed 2-manifolds",
           "not_one_piece": "not one piece (object index)", "uncoloured": "without a colour",
           "nonpositive_volume": "volume not positive", "failures": "failed"}
FLAGS = {"unit_mm": "the unit is not mm", "coloured_by_kind": "not one colour per kind",
         "complete": "the file is incomplete (no END-ISO-10303-21;)"}


def failure_reasons(r: dict) -> list[str]:
    """Plain reasons of a failed check from its figures (the lists of ids, the false flags)."""
    out = [f"{r['error']}"] if r.get("error") else []
    for key, what in REASONS.items():
        items = r.get(key)
        if items:
            count = r.get("failed") if key == "failures" and r.get("failed") else len(items)
            shown = ", ".join(_name(x) for x in items[:5])
            out.append(f"{count} {what}: {shown}{', ...' if count > 5 else ''}")
    out += [what for key, what in FLAGS.items() if r.get(key) is False]
    if r.get("duplicate_ids"):
        out.append(f"{r['duplicate_ids']} duplicate ids")
    for a, b, what in (("solids", "bom_rows", "solids for BOM rows"), ("components", "parts", "components for parts"),
                       ("genus", "expected_genus", "genus, expected"), ("outlines", "expected", "outlines for parts"),
                       ("groups", "expected", "groups for parts")):
        if a in r and b in r and r[a] != r[b]:
            out.append(f"{r[a]} {what} {r[b]}")
    if r.get("status") not in (None, "NoError"):
        out.append(f"manifold3d status {r['status']}")
    if r.get("lint"):
        out += [f"DXF: {x}" for x in r["lint"]]
    elif r.get("audit_errors"):
        out.append(f"{r['audit_errors']} DXF audit errors")
    if "units" in r and r.get("units") != 4:
        out.append(f"DXF units {r['units']}, expected 4 (mm)")
    if "volume_error_mm3" in r and r["volume_error_mm3"] > r.get("float32_bound_mm3", float("inf")):
        out.append(f"volume off by {r['volume_error_mm3']:.3g} mm3, above the float32 bound "
                   f"{r['float32_bound_mm3']:.3g} mm3")
    return out or ["see the JSON (--json) for the figures"]


def _name(x) -> str:
    """One failure of a list: its id (or pair, or file), its figures and its error."""
    if isinstance(x, dict):
        who = str(next((x[k] for k in ("id", "pair", "file") if x.get(k) is not None), "?"))
        if x.get("id") is not None and x.get("file") is not None:
            who = f"{who} in {x['file']}"
        figs = [f"{k} {v:.3g}" for k, v in x.items() if isinstance(v, float)]
        figs += [str(x["error"])] if x.get("error") else []
        return f"{who} ({', '.join(figs)})" if figs else who
    return str(x)


def _holes(bom) -> dict[str, int]:
    """Parts with holes through them (a hub tube: genus 1), from the BOM's ``member`` column."""
    from .cad.parts import GENUS

    return {r["id"]: GENUS[r["member"]] for r in bom if r.get("member") in GENUS}


def _volumes(bom) -> dict[str, float]:
    return {r["id"]: float(r["volume_mm3"]) for r in bom}


def _check_bom(bom) -> dict:
    ids = [r["id"] for r in bom]
    dup = len(ids) - len(set(ids))
    bad = [r["id"] for r in bom if not float(r["volume_mm3"]) > 0]
    kinds = {k: sum(r["kind"] == k for r in bom) for k in ("panel", "beam", "node")}
    return {"pass": dup == 0 and not bad and len(ids) > 0, "rows": len(ids), "duplicate_ids": dup,
            "nonpositive_volume": bad[:20], **kinds}


def _volume_errors(volumes: dict[str, float], expected: dict[str, float], tol: Tolerances):
    """``(worst relative error, its id, ids beyond tol.file_volume)`` of solid volumes against the BOM's."""
    worst, worst_id, errors = 0.0, None, []
    for name, v in volumes.items():
        if name in expected:
            rel = abs(v - expected[name]) / expected[name]
            if rel > worst:
                worst, worst_id = rel, name
            if not rel <= tol.file_volume:   # NaN (no shape) fails
                errors.append(name)
    return worst, worst_id, errors


def _colours_by_kind(names, colours: dict, bom):
    """``(colours per kind, uncoloured ids, one colour per kind and kinds apart)`` of the STEP solids."""
    kind_of = {r["id"]: r["kind"] for r in bom}
    by_kind = {k: sorted({colours[n] for n in names if kind_of.get(n) == k and n in colours})
               for k in set(kind_of.values())}
    by_kind = {k: v for k, v in by_kind.items() if v or any(kind_of.get(n) == k for n in names)}
    uncoloured = [n for n in names if n not in colours]
    ok = (not uncoloured and all(len(c) == 1 for c in by_kind.values())
          and len({c[0] for c in by_kind.values()}) == len(by_kind))
    return by_kind, uncoloured, ok


def _check_step(path, bom, tol: Tolerances = DEFAULT):
    from .export.brep import solid_facts
    from .export.step_read import read_step

    solids, facts = read_step(path)
    names = [n for n, _ in solids]
    expected = _volumes(bom)
    missing = sorted(set(expected) - set(names))
    extra = sorted(set(names) - set(expected))
    invalid, volumes = [], {}
    for name, shape in solids:  # BRepCheck per solid
        f = solid_facts(shape)
        if not f["valid"] or f["solids"] != 1:
            invalid.append(name)
        volumes[name] = f["volume_mm3"]
    worst, worst_id, errors = _volume_errors(volumes, expected, tol)
    unit_mm = "SI_UNIT(.MILLI.,.METRE.)" in _head(path, 1 << 16).replace(" ", "")
    colours = facts.pop("colours", {})
    by_kind, uncoloured, coloured_by_kind = _colours_by_kind(names, colours, bom)
    ok = (not missing and not extra and not invalid and not errors and unit_mm and len(names) == len(expected)
          and coloured_by_kind)
    return ({"pass": ok, "solids": len(names), "bom_rows": len(expected), "missing": missing[:20],
             "unexpected": extra[:20], "invalid": invalid[:20], "n_invalid": len(invalid),
             "volume_rel_error_max": worst, "worst": worst_id, "volume_tolerance": tol.file_volume,
             "volume_failures": errors[:20], "unit_mm": unit_mm, "coloured_by_kind": coloured_by_kind,
             "colours": {k: [list(c) for c in v] for k, v in by_kind.items()}, "uncoloured": uncoloured[:20],
             **facts}, dict(solids))


def _check_step_text(path, bom, tol: Tolerances = DEFAULT):
    """The STEP file read by the independent text reader: names, validity of every solid as a closed
    planar polyhedron (edges used twice in opposite directions, V - E + F = 2, loops closed and
    counter-clockwise about their outward plane normals, simple, vertices on their planes and lines
    within the file's declared uncertainty), volumes against the BOM, unit, colours per kind."""
    from .export.step_text import read_step_text

    solids, facts = read_step_text(path)
    expected = _volumes(bom)
    holes = _holes(bom)
    names = list(solids)
    missing = sorted(set(expected) - set(names))
    extra = sorted(set(names) - set(expected))
    accuracy = facts["uncertainty_mm"] or 1e-6
    invalid, reasons = [], {}
    worst_plane = max((f["on_plane_mm"] for f in solids.values()), default=0.0)
    worst_line = max((f["on_line_mm"] for f in solids.values()), default=0.0)
    for name, f in solids.items():
        bad = [k for k in ("closed", "loops_closed", "normals_agree", "simple") if not f[k]]
        bad += ([f"euler {f['euler']}"] if f["euler"] != 2 - 2 * holes.get(name, 0) else [])
        bad += (["vertex off its plane"] if f["on_plane_mm"] > accuracy else [])
        bad += (["vertex off its line"] if f["on_line_mm"] > accuracy else [])
        bad += (["volume not positive"] if not f["volume_mm3"] > 0 else [])
        if bad:
            invalid.append(name)
            reasons.setdefault(", ".join(bad), name)
    worst, worst_id, errors = _volume_errors({n: f["volume_mm3"] for n, f in solids.items()}, expected, tol)
    colours = {n: f["colour"] for n, f in solids.items() if f["colour"] is not None}
    by_kind, uncoloured, coloured_by_kind = _colours_by_kind(names, colours, bom)
    ok = (not missing and not extra and not invalid and not errors and facts["unit_mm"] and facts["complete"]
          and facts["solids"] == len(expected) and not facts["duplicate_names"] and coloured_by_kind)
    return ({"pass": ok, "read_back": "text", "solids": facts["solids"], "bom_rows": len(expected),
             "missing": missing[:20], "unexpected": extra[:20], "invalid": invalid[:20],
             "n_invalid": len(invalid), "invalid_reasons": reasons, "volume_rel_error_max": worst,
             "worst": worst_id, "volume_tolerance": tol.file_volume, "volume_failures": errors[:20],
             "max_off_plane_mm": worst_plane, "max_off_line_mm": worst_line, "accuracy_mm": accuracy,
             "unit_mm": facts["unit_mm"], "complete": facts["complete"], "coloured_by_kind": coloured_by_kind,
             "colours": {k: [list(c) for c in v] for k, v in by_kind.items()}, "uncoloured": uncoloured[:20],
             "reader": facts["reader"]}, solids)


def _head(path, n: int) -> str:
    with open(path, "rb") as fh:
        return fh.read(n).decode("ascii", errors="replace")


def _check_intersections(meshes, tol):
    from .export.verify import intersections

    return intersections(list(meshes.values()), tol.cad_linear_mm)


def _check_bearing(meshes, bom, tol):
    from .cad.parts import unit_id
    from .export.verify import bearing

    plates: dict[tuple[str, str], list[str]] = {}   # (beam unit, panel) -> the plates the panel lies on
    for r in bom:
        if r["kind"] == "beam":
            for n in r["neighbours"].split():
                if n.startswith("P"):
                    plates.setdefault((unit_id(r["id"]), n), []).append(r["id"])
    supports = {r["id"]: [b for n in r["neighbours"].split() if n.startswith("B")
                          for b in plates.get((n, r["id"]), [n])]
                for r in bom if r["kind"] == "panel"}
    return bearing(meshes, supports, tol.cad_linear_mm)


def _check_flat(path, bom, read):
    from .export.flatdata import check_flat

    return check_flat(path, bom, step_solids=read.get("step"), meshes=read.get("3mf"))


def _check_dxf_keep(path, bom, flat_path=None, reader=None, tol: Tolerances = DEFAULT):
    """:func:`_check_dxf` and the outlines it read (``{id: (k, 2)}``; empty without flat.json), which
    the cut files' check compares theirs with."""
    kept: dict = {}
    return _check_dxf(path, bom, flat_path, reader, tol, kept=kept), kept


def _check_dxf(path, bom, flat_path=None, reader=None, tol: Tolerances = DEFAULT, *, kept: dict | None = None):
    """CUT outlines against the flat data's outlines (which the flat check holds to the STEP solids),
    or, without flat.json, their areas against the BOM's (a beam's true outline, V ends and ridge
    included, is not a face of its solid).  Every outline's id must be a BOM row's (the STEP check
    holds the solids' names to the same rows), so the DXF is read without waiting for the STEP.

    ``reader``: ``"text"`` (the independent DXF reader, linted) or None (ezdxf loads and audits)."""
    from .export.verify import match_outlines

    if reader == "text":
        from .export.dxf_text import read_outlines_text as read_outlines
    else:
        from .export.dxf import read_outlines

    if flat_path is None or not Path(flat_path).exists():  # a beam's true outline is no face of its solid
        from .check_fast import dxf_against_bom

        return dict(dxf_against_bom(path, bom), note="without flat.json: CUT outlines against the BOM areas")
    from .export.flatdata import read_flat

    outline_of = {}
    for g in read_flat(flat_path):
        O = g["outline"]                                                     # (p, k, 2): z = 0 added
        if O.ndim == 3:
            O = np.concatenate([O, np.zeros(O.shape[:-1] + (1,))], axis=-1)
            outline_of.update((pid, [Q]) for pid, Q in zip(g["ids"], O))
            continue
        for pid, Q in zip(g["ids"], O):
            outline_of[pid] = [np.concatenate([Q, np.zeros((len(Q), 1))], axis=1)]
    outlines, facts = read_outlines(path)
    if kept is not None:
        kept.update(outlines)
    flat = [r["id"] for r in bom if cut_from_sheet(r["kind"], r.get("member", ""))]
    rows = {r["id"] for r in bom}
    missing = sorted(set(flat) - set(outlines))
    worst_a, worst_e, worst_id, failures = 0.0, 0.0, None, []
    known = [pid for pid in outlines if pid in rows and pid in outline_of]
    fis, rels, errs = match_outlines([outlines[pid] for pid in known], [outline_of[pid] for pid in known])
    matched = {pid: (int(fi), float(rel), float(err))
               for pid, fi, rel, err in zip(known, fis.tolist(), rels.tolist(), errs.tolist())}
    for pid in outlines:  # one outline per part
        if pid not in rows:
            failures.append({"id": pid, "error": "no BOM row of that id"})
            continue
        if pid not in outline_of:
            failures.append({"id": pid, "error": "not in flat.json"})
            continue
        fi, rel, err = matched[pid]
        if err > worst_e:
            worst_e, worst_id = err, pid
        worst_a = max(worst_a, rel)
        if fi < 0 or not (rel <= tol.file_area and err <= tol.file_edge_mm):   # NaN fails
            failures.append({"id": pid, "face": fi, "area_rel_error": rel, "edge_error_mm": err})
    ok = (facts["audit_errors"] == 0 and facts["units"] == 4 and not missing and not failures
          and facts["texts"] >= len(flat))
    return {"pass": ok, "against": "flat.json", "outlines": len(outlines),
            "expected": len(flat), "missing": missing[:20],
            "area_rel_error_max": worst_a, "edge_error_mm_max": worst_e, "worst": worst_id,
            "tolerances": {"area_rel": tol.file_area, "edge_mm": tol.file_edge_mm}, "failures": failures[:20],
            "failed": len(failures), **facts}


def _check_svg(path, bom):
    """Well-formed XML (expat, in C, no tree), an SVG root, one ``<g id=...>`` per panel and beam."""
    import re
    from xml.parsers import expat
    from xml.sax.saxutils import unescape

    data = Path(path).read_bytes()
    try:
        expat.ParserCreate().Parse(data, True)
    except expat.ExpatError as exc:
        return {"pass": False, "error": f"{path.name}: not well-formed XML ({exc})"}
    root = re.search(rb"<(?:[\w.-]+:)?svg\b[^>]*>", data)
    if root is None or b"http://www.w3.org/2000/svg" not in root.group():
        return {"pass": False, "error": f"{path.name}: the root element is not an SVG <svg> element"}
    ids = {unescape(m.decode("utf-8", "replace"), {"&quot;": '"', "&apos;": "'"})
           for m in re.findall(rb"<g\s[^>]*?\bid=\"([^\"]*)\"", data)}
    flat = {r["id"] for r in bom if cut_from_sheet(r["kind"], r.get("member", ""))}
    missing = sorted(flat - ids)
    return {"pass": not missing, "groups": len(ids & flat), "expected": len(flat), "missing": missing[:20]}
