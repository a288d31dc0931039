"""``fabricate remesh SURFACE --edge-length L -o quads.obj``: triangle surface to a conical quad mesh."""
from __future__ import annotations

import json

from .args import add_output
from .units import add_units


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
    p.add_argument("surface", help="triangle or polygon mesh (.obj, .off, .ply, .stl): one piece, open "
                                   "(holes allowed)")
    p.add_argument("--edge-length", type=float, required=True, help="target edge length (mm)")
    add_output(p, "output quad mesh (.obj, .off, .ply)")
    p.add_argument("--radius", type=float, default=None,
                   help="kernel radius of the principal directions, mm (default: the edge length, at "
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
    add_units(p, "SURFACE (the quad mesh is written in the same unit)")
    p.set_defaults(handler=run)


def run(args) -> int:
    from optimize.atomic import atomic_open
    from optimize.mesh.io import write_mesh
    from optimize.remesh.quads import surface_to_mesh

    from .units import read_mm, to_file_units

    surface = read_mm(args.surface, args.units)
    mesh, res, rep = surface_to_mesh(surface, args.edge_length, target=args.optimize, radius=args.radius,
                                     side=args.side, glide_boundary=not args.free_boundary,
                                     irregular=args.irregular)
    from .cmd_optimize import _marks

    write_mesh(args.output, to_file_units(mesh, args.units), comments=_marks(res))
    facts = {"input": args.surface, "output": args.output, "units": args.units, "lengths": "mm",
             "remesh": rep.as_dict(), "notes": mesh.notes}
    if res is not None:
        facts["optimize"] = {"target": args.optimize, "status": res.status, "success": res.success,
                             "message": res.message, "iterations": res.nit,
                             "max_distance_rel": res.max_distance}
    if args.report:
        with atomic_open(args.report, "w") as fh:
            json.dump(facts, fh, indent=2, default=str)
    sizes = ", ".join(f"{c} {k}-gons" for k, c in rep.face_sizes.items())
    print(f"{args.output}: {mesh.n_vertices} vertices, {sizes} (written in {args.units}); edge length mean "
          f"{rep.edge_length['mean']:.4g} mm (target {args.edge_length:g} mm), radius {rep.radius:.4g} mm")
    for note in mesh.notes:
        print(f"note: {note}")
    if res is None:
        return 0
    print(f"{args.optimize}: {res.status} after {res.nit} iterations ({res.message}); "
          f"max distance to the surface {res.max_distance:.3g} x bbox diagonal "
          f"({res.max_distance * surface.bbox_diagonal():.3g} mm)")
    return 0 if res.success else 3
