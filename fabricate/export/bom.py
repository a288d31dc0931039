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

from optimize.atomic import atomic_open
from optimize.errors import ExportError

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
        raise ExportError(f"{path}: cannot write the bill of materials ({exc.strerror or exc})") from None
    return {"file": path.name, "bytes": path.stat().st_size, "rows": rows,
            "mass_kg": {k: round(v, 3) for k, v in mass.items()}, "seconds": time.perf_counter() - t0}


def read_bom(path) -> list[dict]:
    """Rows of a bill of materials as dicts (strings), in file order."""
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
    except OSError as exc:
        raise ExportError(f"{path}: cannot read the bill of materials ({exc.strerror or exc})") from None
    if rows and set(COLUMNS) - set(rows[0]):
        raise ExportError(f"{path}: columns {sorted(set(COLUMNS) - set(rows[0]))} missing; expected {COLUMNS}")
    return rows
