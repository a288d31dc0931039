"""``fabricate offset MESH --distances 0,20,120 -o DIR``: layers, node axes, beams, report."""
from __future__ import annotations

import math

from .args import add_output
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
                    "named, and exits 3. The output files are in mm whatever --units says. DIR follows the "
                    "rules of a run folder (fabricate run): written atomically with a marker; an existing "
                    "DIR is replaced only when it is an earlier offset output of this tool with no files "
                    "added or changed, and only with --replace; a result that is not PQ (exit 3) never "
                    "replaces a passing one (it is written beside it as DIR.failed-<time>/).")
    p.add_argument("mesh", help="mesh file (.obj, .off, .ply, .stl, .3dm), in --units")
    p.add_argument("--distances", required=True, metavar="D1,D2,...",
                   help="comma-separated signed distances in mm whatever --units says (part dimensions, as "
                        "offset.distances in a config), e.g. 0,20,120 (use --distances=-20,0 for a leading "
                        "minus); beams span the first and the last")
    add_output(p, "output folder (written atomically, with a marker file; never a folder this tool did not "
                  "write)", metavar="DIR")
    p.add_argument("--replace", action="store_true",
                   help="replace an earlier offset output in DIR (as fabricate run --force; --force here "
                        "means offsetting a mesh that is not PQ)")
    p.add_argument("--flip", action="store_true", help="reverse the face normals (offset to the other side)")
    p.add_argument("--force", action="store_true", help="offset a mesh that is not PQ and report (exit 3)")
    p.add_argument("--free-axes", choices=("planar_beams", "min_norm"), default="planar_beams",
                   help="axes the faces leave free (boundary, cylinder-like vertices): turned for planar "
                        "beams (default) or the bisector of the face normals")
    add_units(p, "MESH (the output files are in mm)", default=None)
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


def run(args) -> int:
    from pathlib import Path

    from optimize.atomic import remove_part
    from optimize.errors import MeshError
    from optimize.tolerances import Tolerances

    from .. import runfolder
    from ...offset import offset_structure, require_pq, write_offset_files
    from .units import UNIT_TO_MM, read_mm, resolve_units

    texts, values = parse_distances(args.distances)
    out = Path(args.output)
    runfolder.check_target(out, force=True, flag="--replace")  # said before reading the mesh
    args.units = resolve_units(args.mesh, args.units)
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
    r = s.report
    code = 3 if not r["is_pq"] or not r["turned_over"]["ok"] else 0
    runfolder.make_parent(out, "-o")
    for note in runfolder.clean_stale_parts(out.parent, out.name):
        print(note)
    with runfolder.run_lock(out):
        previous = runfolder.check_target(out, args.replace, flag="--replace")
        tmp = runfolder.new_part(out)
        try:
            names = write_offset_files(s, tmp, texts, extra)
            runfolder.write_marker(tmp, {"name": out.name, "command": "offset", "status": r["status"],
                                         "exit_code": code})
            previous = runfolder.check_target(out, args.replace, flag="--replace")  # changed meanwhile?
            dest, beside = runfolder.publish_run(tmp, out, previous, code)
        except BaseException:
            remove_part(tmp)
            raise
    if beside:
        print(beside)
    print(f"{mesh.name}: {mesh.n_vertices} vertices, {mesh.n_faces} faces, bounding-box diagonal "
          f"{mesh.bbox_diagonal():,.1f} mm (file in {args.units}) -> {dest}/ "
          f"({len(names)} files in mm: {', '.join(names[:len(texts)])}, axes, beams, offset_report.json)")
    print(f"status: {r['status']}" + (" (forced: the mesh is not PQ)" if not r["is_pq"] else ""))
    for line in r["summary"]:
        print(line)
    return code
