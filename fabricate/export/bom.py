"""Bill of materials (CSV): one row per solid in the STEP file.

Columns: ``id, kind, element`` (mesh face / edge / vertex index),
``mesh_vertices`` (space separated), ``area_m2`` (outline face),
``length_mm`` (beams and nodes; a hub tube: its cut between the caps), ``thickness_mm`` (a panel's
ply, a plate's thickness; a hub tube: its wall; a solid hub: its diameter), ``volume_mm3`` (analytic,
full precision: ``fabricate check`` compares the STEP solids with it),
``weight_kg`` (volume x density), ``rect_w_mm, rect_h_mm`` (smallest
bounding rectangle of the flat outline and bevel), ``planarity_mm`` (how far
the source polygon was from the plane the part was built in),
``residual_mm`` (construction round-off), ``neighbours`` (ids in contact,
space separated), ``unit`` (the part a solid belongs to: ``P0001`` for the plies
``P0001.1 ...`` of a glass unit, else its own id), ``member`` (what the solid is in
its unit: ``ply 1``, ``inner interlayer 1``, ``web``, ``top flange +``, ``tube``; empty for a one-solid part),
``material`` (``glass``, ``PVB``, ``SGP``, ``steel``; its density gives the weight).
"""
from __future__ import annotations

import csv
import time
from pathlib import Path

import numpy as np

from optimize.atomic import atomic_open
from optimize.errors import ExportError, write_error

COLUMNS = ("id", "kind", "element", "mesh_vertices", "area_m2", "length_mm", "thickness_mm", "volume_mm3",
           "weight_kg", "rect_w_mm", "rect_h_mm", "planarity_mm", "residual_mm", "neighbours", "unit", "member",
           "material")


def _mesh_vertices(group, mesh) -> list[str]:
    if mesh is None:
        return [""] * len(group)
    if group.kind == "panel":
        return [" ".join(str(v) for v in mesh.F[f][mesh.F[f] >= 0].tolist()) for f in group.element.tolist()]
    if group.kind == "beam":
        E = mesh.topology.edges[group.element]
        return [f"{a} {b}" for a, b in E.tolist()]
    return [str(v) for v in group.element.tolist()]


def write_bom(parts, path, *, mesh=None) -> dict:
    """Write the bill of materials (atomic).  ``mesh`` (optional) fills ``mesh_vertices``.

    Returns facts: ``file, bytes, rows, mass_kg`` per kind, ``seconds``.
    """
    t0 = time.perf_counter()
    path = Path(path)
    mesh = mesh if mesh is not None else getattr(parts, "mesh", None)
    mass: dict[str, float] = {}
    rows = 0
    try:
        with atomic_open(path, "w", encoding="utf-8", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(COLUMNS)
            for g in parts.groups:
                density = parts.spec.group_density(g)
                material = g.material or ("glass" if g.kind == "panel" else "steel")
                weight = g.volume_mm3 * density * 1e-9
                mass[g.kind] = mass.get(g.kind, 0.0) + float(weight.sum())
                verts = _mesh_vertices(g, mesh)
                for i, pid in enumerate(g.ids):  # one CSV row per part
                    w.writerow((pid, g.kind, int(g.element[i]), verts[i], f"{g.area_mm2[i] * 1e-6:.6f}",
                                f"{g.length_mm[i]:.3f}", f"{g.thickness_mm[i]:.3f}", repr(float(g.volume_mm3[i])),
                                f"{weight[i]:.3f}", f"{g.rect[i, 0]:.3f}", f"{g.rect[i, 1]:.3f}",
                                f"{g.planarity_mm[i]:.3g}", f"{g.residual_mm[i]:.3g}", " ".join(g.neighbours[i]),
                                pid.split(".", 1)[0], g.member, material))
                    rows += 1
    except OSError as exc:
        raise write_error(path, "bill of materials", exc) from exc
    return {"file": path.name, "bytes": path.stat().st_size, "rows": rows,
            "mass_kg": {k: round(v, 3) for k, v in mass.items()}, "seconds": time.perf_counter() - t0}


NUMBERS = ("element", "area_m2", "length_mm", "thickness_mm", "volume_mm3", "weight_kg", "rect_w_mm", "rect_h_mm")
"""Columns that :func:`read_bom` holds to be finite numbers (``planarity_mm``, ``residual_mm``: numbers)."""


def read_bom(path) -> list[dict]:
    """Rows of a bill of materials as dicts (strings), in file order; a file that is not one (a row of
    too many or too few fields, a number column that is not a finite number, not UTF-8) is refused
    with an :class:`ExportError` naming the line, the column and the value."""
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            reader = csv.DictReader(fh)
            rows = list(reader)
    except OSError as exc:
        raise ExportError(f"{path}: cannot read the bill of materials ({exc.strerror or exc})") from None
    except (UnicodeDecodeError, csv.Error) as exc:
        raise ExportError(f"{path}: not a bill of materials in CSV ({exc}); expected the bom.csv of a run") from None
    if rows and set(COLUMNS) - set(rows[0]):
        raise ExportError(f"{path}: columns {sorted(set(COLUMNS) - set(rows[0]))} missing; expected {COLUMNS}")
    for i, r in enumerate(rows):
        if None in r or None in r.values():
            n = sum(v is not None for k, v in r.items() if k is not None) + len(r.get(None) or ())
            raise ExportError(f"{path}: line {i + 2} has {n} fields, expected {len(reader.fieldnames)} (the columns)")
    for col in NUMBERS + ("planarity_mm", "residual_mm"):
        values = [r[col] for r in rows]
        try:
            x = np.array(values, dtype=float)
            good = np.isfinite(x) if col in NUMBERS else np.ones(len(x), bool)
        except ValueError:
            good = np.array([_is_number(v) for v in values], dtype=bool)
        if not good.all():
            i = int(np.argmin(good))
            raise ExportError(f"{path}: line {i + 2} column {col}: {values[i][:40]!r}; expected a "
                              f"{'finite ' if col in NUMBERS else ''}number")
    return rows


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
