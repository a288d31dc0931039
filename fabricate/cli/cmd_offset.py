"""``fabricate offset MESH --distances 0,20,120 -o DIR``: layers, node axes, beams, report."""
from __future__ import annotations

import math

from .units import add_units


def register(sub) -> None:
    p = sub.add_parser(
        "offset", help="offset layers at constant face distance, node axes and beams (paper section 4)",
        description="Offset a PQ (ideally conical) mesh: one layer per distance (layer_<d>.obj, same "
                    "vertex order and faces), node axes and beam quads (OBJ + JSON) and "
                    "offset_report.json with every tolerance in mm and the worst elements named. "
                    "A mesh that is not PQ is refused (exit 2) unless --force (then exit 3: results "
                    "written and marked); a PQ mesh that is not conical is offset and the report "
                    "says by how much faces miss their distance and beams twist. A distance past the "
                    "focal distance of a face (the offset face turns over) is reported with the faces "
                    "named, and exits 3. The output files are in mm whatever --units says.")
    p.add_argument("mesh", help="mesh file (.obj, .off, .ply), in --units (default mm)")
    p.add_argument("--distances", required=True, metavar="D1,D2,...",
                   help="comma-separated signed distances in mm, e.g. 0,20,120 (use --distances=-20,0 "
                        "for a leading minus); beams span the first and the last")
    p.add_argument("-o", "--output", required=True, metavar="DIR",
                   help="output folder (written atomically; an existing offset output folder is replaced)")
    p.add_argument("--flip", action="store_true", help="reverse the face normals (offset to the other side)")
    p.add_argument("--force", action="store_true", help="offset a mesh that is not PQ and report (exit 3)")
    p.add_argument("--free-axes", choices=("planar_beams", "min_norm"), default="planar_beams",
                   help="axes the faces leave free (boundary, cylinder-like vertices): turned for planar "
                        "beams (default) or the bisector of the face normals")
    add_units(p)
    p.set_defaults(handler=run)


def parse_distances(text: str) -> tuple[list[str], list[float]]:
    """``"0,20,120"`` -> (["0", "20", "120"], [0.0, 20.0, 120.0]); ConfigError naming the bad item."""
    from optimize.errors import ConfigError

    items = [t.strip() for t in text.split(",")]
    values = []
    for i, t in enumerate(items):
        try:
            d = float(t)
        except ValueError:
            d = math.nan
        if not t or not math.isfinite(d):
            raise ConfigError(f"--distances {text!r}: item {i + 1} {t!r} is not a finite number, "
                              "expected comma-separated distances in mm such as 0,20,120")
        if d in values:
            raise ConfigError(f"--distances {text!r}: {t!r} repeats the distance {d:g}, "
                              "expected distinct distances")
        values.append(d)
    return items, values


def _check_output(path) -> None:
    """Refuse to replace a non-empty folder that is not an earlier offset output."""
    from optimize.errors import ConfigError

    from ..offset.files import REPORT

    if path.exists() and (not path.is_dir() or (any(path.iterdir()) and not (path / REPORT).exists())):
        raise ConfigError(f"-o {path}: exists and is not an offset output folder (no {REPORT}), "
                          "expected a new or earlier offset output folder (it is replaced)")


def run(args) -> int:
    from pathlib import Path

    from optimize.atomic import atomic_dir
    from optimize.errors import MeshError
    from optimize.tolerances import Tolerances

    from ..offset import offset_structure, require_pq, write_offset_files
    from .units import UNIT_TO_MM, read_mm

    texts, values = parse_distances(args.distances)
    out = Path(args.output)
    _check_output(out)
    mesh = read_mm(args.mesh, args.units)
    tol = Tolerances()
    if not args.force:
        try:
            require_pq(mesh, tol)
        except MeshError as exc:
            raise MeshError(f"{exc}; or run with --force to offset it anyway and read the report") from None
    s = offset_structure(mesh, values, flip=args.flip, tol=tol, free_axes=args.free_axes)
    extra = {"input": {"path": str(args.mesh), "forced": bool(args.force), "notes": list(mesh.notes),
                       "units": args.units, "mm_per_unit": UNIT_TO_MM[args.units]}}
    with atomic_dir(out) as tmp:
        names = write_offset_files(s, tmp, texts, extra)
    r = s.report
    print(f"{mesh.name}: {mesh.n_vertices} vertices, {mesh.n_faces} faces, bounding-box diagonal "
          f"{mesh.bbox_diagonal():,.1f} mm (file in {args.units}) -> {out}/ "
          f"({len(names)} files in mm: {', '.join(names[:len(texts)])}, axes, beams, offset_report.json)")
    print(f"status: {r['status']}" + (" (forced: the mesh is not PQ)" if not r["is_pq"] else ""))
    for line in r["summary"]:
        print(line)
    turned = r["turned_over"]
    return 3 if not r["is_pq"] or not turned["ok"] else 0
