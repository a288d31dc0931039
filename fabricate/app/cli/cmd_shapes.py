"""``fabricate shapes [NAME -o OUT] [--param k=v ...]``: list the built-in designs or write one."""
from __future__ import annotations

import json

from .args import add_output
from .units import add_units


def register(sub) -> None:
    p = sub.add_parser("shapes", help="list the built-in designs, or write one's starting mesh",
                       description="Without NAME: list the built-in designs with their parameters "
                                   "and defaults (all sizes in mm). With NAME and -o: write the "
                                   "design's starting mesh (its control mesh when it has "
                                   "subdivision levels) to OUT (.obj, .off, .ply).")
    p.add_argument("name", nargs="?", help="design name (see the list)")
    add_output(p, "mesh file to write (.obj, .off, .ply)", required=False)
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                   help="set a design parameter (repeatable), e.g. --param nu=12 --param noise=0.05")
    p.add_argument("--refined", action="store_true",
                   help="write the mesh after the design's subdivision levels, not perturbed")
    p.add_argument("--json", action="store_true", help="list as JSON")
    add_units(p, "the written mesh (the designs are in mm; with --units m the file is in metres)")
    p.set_defaults(handler=run)


def run(args) -> int:
    from optimize.modelling.designs import DESIGNS, describe, parse_params
    from optimize.errors import ConfigError

    if args.name is None:
        if args.output or args.param or args.refined:
            raise ConfigError("fabricate shapes: -o, --param and --refined need a design NAME")
        items = describe()
        if args.json:
            print(json.dumps(items, indent=2, default=str))
        else:
            _print_list(items)
        return 0
    params = parse_params(args.name, args.param)
    design = DESIGNS[args.name](**params)
    mesh = design.mesh
    if args.refined and design.levels:
        from fabricate.app.config_design import MAX_FACES, subdivided_faces
        from optimize.modelling.subdivision import subdivide

        if subdivided_faces(mesh.n_faces, design.scheme, design.levels) > MAX_FACES:
            raise ConfigError(f"fabricate shapes {args.name} --refined: {mesh.n_faces:,} faces and {design.levels} "
                              f"rounds of {design.scheme} make about "
                              f"{subdivided_faces(mesh.n_faces, design.scheme, design.levels):,} faces, more than "
                              f"{MAX_FACES:,}; expected smaller counts or --param levels=...")
        mesh, _ = subdivide(mesh, design.scheme, design.levels)
    if args.output is None:
        print(f"{design.name}: {mesh.n_vertices} vertices, {mesh.n_faces} faces ({design.units}); "
              f"levels {design.levels} {design.scheme}, target {design.target}. Give -o OUT to write it.")
        return 0
    from optimize.mesh.io import write_mesh

    from .units import UNIT_TO_MM, to_file_units

    if design.units != "mm":  # designs say their unit; --units is the file's
        mesh = mesh.with_vertices(mesh.V * UNIT_TO_MM[design.units])
    write_mesh(args.output, to_file_units(mesh, args.units))
    if args.refined and design.levels:
        what = f"subdivided ({design.levels} level(s) of {design.scheme}, not perturbed)"
    elif design.levels:
        what = f"control (run {design.levels} level(s) of {design.scheme} on it)"
    else:
        what = "starting"
    print(f"wrote {args.output}: {design.name} {what} mesh, {mesh.n_vertices} vertices, "
          f"{mesh.n_faces} faces, units {args.units}; target {design.target}")
    return 0


def _print_list(items: list[dict]) -> None:
    for d in items:
        print(f"{d['name']}: {d['summary']}")
        print(f"    starts with {d['vertices']} vertices, {d['faces']} faces; levels {d['levels']} "
              f"{d['scheme'] if d['levels'] else ''}, target {d['target']}; units {d['units']}")
        for p in d["params"]:
            print(f"    {p['name']:<12} = {p['default']!s:<10} {p['help']}")
        print()
