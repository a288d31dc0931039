"""``fabricate remesh SURFACE --edge-length L -o quads.obj``: triangle surface to a conical quad mesh."""
from __future__ import annotations

import json

from .args import add_output
from .units import add_units, positive_length


def _vector(text: str):
    import argparse

    if text == "keep":
        return text
    try:
        v = [float(x) for x in text.split(",")]
    except ValueError:
        v = []
    if len(v) != 3:
        raise argparse.ArgumentTypeError(f"{text!r}: expected three numbers x,y,z (a vector toward the inside) or 'keep'")
    return v


def register(sub) -> None:
    p = sub.add_parser(
        "remesh", help="triangle surface -> quad mesh along principal curvature lines -> conical",
        description="Estimate principal directions of a triangle surface (roof, facade, canopy; "
                    "one piece, with one or more boundary loops) by volume PCA at kernel radius R, "
                    "integrate them into a quad-dominant mesh with the given edge length (umbilics "
                    "become 3-/5-gons or valence-3/5 vertices), then optimize it to a conical (or "
                    "circular) mesh close to the surface.  Exit 3 when the optimization misses a tolerance "
                    "(the mesh is written all the same, and the report says so).")
    p.add_argument("surface", help="triangle or polygon mesh (.obj, .off, .ply, .stl, .3dm): one piece, open "
                                   "(holes allowed)")
    p.add_argument("--edge-length", type=positive_length, required=True, metavar="L",
                   help="target edge length, in --units (--units m --edge-length 1.5: 1.5 m); refused (exit 2) "
                        "when the surface's area / L^2 is more than 2,000,000 faces or needs half the memory")
    add_output(p, "output quad mesh (.obj, .off, .ply)")
    p.add_argument("--radius", type=positive_length, default=None, metavar="R",
                   help="kernel radius of the principal directions, in --units (default: the edge length, at "
                        "least 3 mean triangle edges)")
    p.add_argument("--side", type=_vector, default=None,
                   help="x,y,z: direction toward the inside of the surface (default 0,0,-1: below; "
                        "write --side=-1,0,0 when it starts with a minus), or 'keep': the file's face "
                        "orientation says which side is outside (a tube, a tunnel)")
    p.add_argument("--optimize", choices=("conical", "circular", "pq", "none"), default="conical",
                   help="optimization after remeshing (default conical)")
    p.add_argument("--irregular", choices=("faces", "vertices", "nearest"), default="faces",
                   help="what a kept singularity becomes: a 3-/5-gon (default), a valence-3/5 vertex, "
                        "or whichever the parametrization's rounding gives")
    p.add_argument("--free-boundary", action="store_true",
                   help="let boundary vertices move freely instead of gliding along the boundary")
    p.add_argument("--report", default=None, help="write a JSON report here (lengths in mm)")
    add_units(p, "SURFACE, --edge-length and --radius (the quad mesh is written in the same unit)", default=None)
    p.set_defaults(handler=run)


def run(args) -> int:
    from optimize.atomic import atomic_open
    from optimize.mesh.io import write_mesh
    from optimize.remesh.quads import check_remesh_size, surface_to_mesh

    from .units import UNIT_TO_MM, length_mm, read_mm, resolve_units, to_file_units

    args.units = resolve_units(args.surface, args.units)
    surface = read_mm(args.surface, args.units)
    h = length_mm(args.edge_length, args.units)
    check_remesh_size(surface, h, key="--edge-length", unit=args.units, per_unit=UNIT_TO_MM[args.units])
    radius = None if args.radius is None else length_mm(args.radius, args.units)
    mesh, res, rep = surface_to_mesh(surface, h, target=args.optimize, radius=radius,
                                     side=args.side, glide_boundary=not args.free_boundary,
                                     irregular=args.irregular)
    from .cmd_optimize import _marks

    write_mesh(args.output, to_file_units(mesh, args.units), comments=_marks(res))
    facts = {"input": args.surface, "output": args.output, "units": args.units, "lengths": "mm",
             "edge_length": {"given": args.edge_length, "units": args.units, "mm": h},
             "remesh": rep.as_dict(), "notes": mesh.notes}
    if res is not None:
        facts["optimize"] = {"target": args.optimize, "status": res.status, "success": res.success,
                             "message": res.message, "iterations": res.nit,
                             "max_distance_rel": res.max_distance}
    if args.report:
        with atomic_open(args.report, "w") as fh:
            json.dump(facts, fh, indent=2, default=str)
    sizes = ", ".join(f"{c} {k}-gons" for k, c in rep.face_sizes.items())
    target = f"{h:.4g} mm" + (f" = {args.edge_length:g} {args.units}" if args.units != "mm" else "")
    print(f"{args.output}: {mesh.n_vertices} vertices, {sizes} (written in {args.units}); edge length mean "
          f"{rep.edge_length['mean']:.4g} mm (target {target}), radius {rep.radius:.4g} mm")
    for note in mesh.notes:
        print(f"note: {note}")
    if res is None:
        return 0
    print(f"{args.optimize}: {res.status} after {res.nit} iterations ({res.message}); "
          f"max distance to the surface {res.max_distance:.3g} x bbox diagonal "
          f"({res.max_distance * surface.bbox_diagonal():.3g} mm)")
    return 0 if res.success else 3
