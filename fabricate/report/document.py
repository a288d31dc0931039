"""report.json: what was run, with which versions, how long each stage took, and every
measure with its tolerance, pass/fail and worst elements (relative and mm)."""
from __future__ import annotations

import datetime as _dt
import json
import math
import platform
from importlib import metadata
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from optimize.atomic import atomic_open
from optimize.errors import writing

from .totals import client_totals

SCHEMA = "conical-fab/report/1"
DISTRIBUTIONS = ("conical-fab", "numpy", "scipy", "pydantic", "PyYAML", "matplotlib", "rich",
                 "build123d", "cadquery-ocp", "manifold3d", "ezdxf")


def versions() -> dict[str, str | None]:
    """Installed versions of the packages a result depends on (None: not installed)."""
    out: dict[str, str | None] = {"python": platform.python_version(), "platform": platform.platform()}
    for dist in DISTRIBUTIONS:
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = None
    from fabricate import __version__

    out["fabricate"] = __version__
    return out


def jsonable(value: Any) -> Any:
    """A JSON-ready copy: numpy to Python, NaN and infinities to None, paths to strings."""
    if isinstance(value, Mapping):  # dicts and the records' read-only views
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, Path):
        return str(value)
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return str(value)


def parts_summary(parts) -> dict[str, Any] | None:
    """Counts, volumes (mm3) and masses (kg) per kind of part, plus the CAD stage's own report."""
    if parts is None:
        return None
    out: dict[str, Any] = {}
    for kind in ("panel", "beam", "node"):
        groups = parts.of_kind(kind)
        vol = float(sum(float(np.sum(g.volume_mm3)) for g in groups))
        density = parts.spec.density(kind)
        mass = sum(float(np.sum(g.volume_mm3)) * parts.spec.group_density(g) for g in groups) * 1e-9
        out[kind + "s"] = {"count": int(sum(len(g) for g in groups)),    # solids (plates, plies, hub pieces)
                           "units": len({i.split(".", 1)[0] for g in groups for i in g.ids}), "volume_mm3": vol,
                           "mass_kg": mass, "density_kg_m3": density}
    from fabricate.cad.glass import bearing_groups

    out["panels"].update(units=sum(len(g) for g in bearing_groups(parts)), build_up=parts.spec.glass.describe())
    out["total"] = {"count": len(parts), "mass_kg": sum(v["mass_kg"] for v in out.values())}
    out["edge_mode"] = parts.edge_mode
    out["cad_report"] = parts.report
    return out


def build_report(run, pictures: dict[str, str], own_files: Mapping[str, Mapping] | None = None) -> dict[str, Any]:
    """The report dict of a finished run, from ``run`` (:class:`fabricate.app.records.RunRecord`) alone;
    ``pictures`` and ``own_files`` are what the report stage itself wrote (captions, facts)."""
    cfg = run.config
    result = run.optimize.result
    structure = run.offset.structure
    mesh = run.optimize.mesh
    out = run.outcome
    known = {**run.exports.files, **(own_files or {})}
    files = {}
    for p in sorted(run.workdir.rglob("*")):
        if p.is_file() and p.name not in ("report.json", "report.html"):
            rel = p.relative_to(run.workdir).as_posix()
            files[rel] = dict(known.get(rel, {}), bytes=p.stat().st_size)
    facts = dict(run.input.facts)
    if run.optimize.routes:
        facts["routes"] = list(run.optimize.routes)
    report = {
        "schema": SCHEMA,
        "name": cfg.name,
        "status": out.status,
        "exit_code": out.exit_code,
        "message": out.message,
        "decision": run.optimize.decision,  # a user's own mesh: the route taken and why (fabricate.app.decide)
        "failed": list(out.failed),
        "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "config_file": str(cfg.source) if cfg.source else None,
        "config": cfg.as_dict(),
        "input": facts,
        "result_mesh": None if mesh is None else {
            "faces": mesh.n_faces, "vertices": mesh.n_vertices, "edges": int(len(mesh.topology.edges)),
            "bbox_diagonal_mm": mesh.bbox_diagonal()},
        "versions": versions(),
        "timings_s": dict(run.timings),
        "measures": run.measures,
        "optimization": result.report() if result is not None else None,
        "levels": list(run.optimize.levels),
        "offset": getattr(structure, "report", None),
        "totals": client_totals(run.parts.parts),
        "parts": parts_summary(run.parts.parts),
        "structure": run.structure.report,
        "check": run.exports.check,
        "files": files,
        "pictures": pictures,
        "notes": list(run.notes),
    }
    return jsonable(report)


def write_report_json(report: dict[str, Any], path: str | Path) -> Path:
    """Write ``report`` as strict JSON (no NaN), atomically."""
    text = json.dumps(report, indent=2, allow_nan=False) + "\n"
    with writing(path, "report", needed=len(text.encode())), atomic_open(path) as fh:
        fh.write(text)
    return Path(path)
