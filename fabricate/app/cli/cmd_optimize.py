"""``fabricate optimize MESH -o OUT``: make a mesh PQ, conical or circular."""
from __future__ import annotations

import json
import sys

from optimize.options import DEFAULTS, FORMULATIONS, LINEAR_SOLVERS, METHODS, TARGETS

from .args import add_output
from .units import add_units


def register(sub) -> None:
    p = sub.add_parser(
        "optimize", help="make every face planar (and the mesh conical or circular)",
        description="Move the vertices of a quad(-dominant) mesh as little as possible so that every "
                    "face is planar, and optionally the mesh is conical or circular. OUT has the same "
                    "vertex order and faces as MESH. Exit 3 when a tolerance was not reached (OUT and "
                    "the report are still written and say so).")
    p.add_argument("mesh", help="input mesh (.obj, .off, .ply)")
    add_output(p, "optimized mesh to write (.obj, .off, .ply)")
    p.add_argument("--target", choices=TARGETS, default=DEFAULTS.target,
                   help="pq: planar faces; conical: PQ + conical vertices (node axes); circular: PQ + "
                        "circular quads; strip: developable strip (the paper's methods: --method default runs "
                        "penalty there, as fabricate run does). Default pq.")
    p.add_argument("--method", choices=METHODS, default=DEFAULTS.method,
                   help="default: regularized Gauss-Newton; penalty/sqp/hybrid: the paper's methods")
    p.add_argument("--formulation", choices=FORMULATIONS, default=DEFAULTS.formulation,
                   help="default method's unknowns: auxiliary (positions + normals, axes, centres; "
                        "quadratic rows), vertices (positions only), auto (vertices for conical)")
    p.add_argument("--linear-solver", choices=LINEAR_SOLVERS,
                   default=DEFAULTS.linear_solver, help="sparse solver of the default method (auto: MKL PARDISO "
                                        "where installed, else SuperLU)")
    p.add_argument("--torsion-free-beams", choices=("auto", "on", "off"), default="auto",
                   help="conical: solve node axes with every interior beam planar (auto: when the mesh "
                        "has interior vertices of valence other than 4)")
    p.add_argument("--no-convex", dest="convex", action="store_false",
                   help="default method: let corners that are convex in the input turn reflex (the "
                        "earlier behaviour: planar, perhaps dented panels, status folded); by default "
                        "convexity is a constraint")
    p.add_argument("--remesh", choices=("auto", "always", "never"), default="never",
                   help="a way forward when the mesh lines are far from a conjugate net: also remesh "
                        "the input (as a surface) along principal directions and optimize that; auto: "
                        "when the input's own lines do not end fold-free and exact; always: take the "
                        "remeshed mesh (OUT then has new faces); never (default): OUT keeps MESH's faces")
    p.add_argument("--fix", default="none", metavar="{boundary,corners,none}",
                   help="vertices that must not move (default none)")
    p.add_argument("--glide", action="store_true", help="boundary vertices glide on the boundary curve")
    p.add_argument("--reference", help="reference surface to stay close to (default: the input)")
    p.add_argument("--fairness", type=float, default=DEFAULTS.fairness, metavar="W",
                   help=f"fairness weight ({DEFAULTS.fairness:g})")
    p.add_argument("--closeness", type=float, default=DEFAULTS.closeness, metavar="W",
                   help=f"closeness weight ({DEFAULTS.closeness:g})")
    p.add_argument("--tol", type=float, default=None, metavar="T",
                   help="tolerance for planarity and the conical/circular defect "
                        f"(default {DEFAULTS.tol.planarity:g})")
    p.add_argument("--max-iter", type=int, default=DEFAULTS.max_iter, metavar="N",
                   help=f"iteration budget ({DEFAULTS.max_iter})")
    p.add_argument("--report", metavar="JSON", help="write the run report (defects, history, timings)")
    p.add_argument("--progress", choices=("auto", "on", "off"), default="auto",
                   help="a progress line per iteration on stderr (auto: when stderr is a terminal)")
    add_units(p, "the mesh files (MESH, --reference; OUT is written in the same unit)", default=None)
    p.set_defaults(handler=run)


def run(args) -> int:
    from optimize import ConfigError, Tolerances, optimize_mesh
    from optimize.atomic import atomic_open
    from optimize.mesh.io import write_mesh
    from optimize.mesh.measures import check_range
    from optimize.result import TARGET_MEASURES

    from ..quads import CLI_HINT, require_quads
    from .units import read_mm, resolve_units, to_file_units

    if args.fix not in ("boundary", "corners", "none"):
        raise ConfigError(f"--fix: {args.fix!r}, expected boundary, corners or none")
    tol = Tolerances()
    if args.tol is not None:
        if not args.tol > 0:
            raise ConfigError(f"--tol: {args.tol!r}, expected a positive number")
        tol = tol.replace(planarity=args.tol, conical=args.tol, circular=args.tol)
    args.units = resolve_units(args.mesh, args.units)  # --units, else a .3dm file's model unit, else mm
    mesh = read_mm(args.mesh, args.units)
    check_range(mesh, str(args.mesh))
    require_quads(mesh, str(args.mesh), hint=CLI_HINT)
    reference = read_mm(args.reference, args.units) if args.reference else None
    if reference is not None:
        check_range(reference, str(args.reference))
    if args.target != "strip":  # said before optimizing: is a fold-free mesh likely near?
        from optimize.mesh.conjugacy import net_defect

        print(f"{mesh.name}: {net_defect(mesh).line(args.target)}")
    from ..stages import method_for

    kwargs = dict(method=method_for(args.target, args.method), fixed=None if args.fix == "none" else args.fix,
                  glide_boundary=args.glide, fairness=args.fairness, closeness=args.closeness, tol=tol,
                  max_iter=args.max_iter,
                  **({} if args.method != "default" else
                     dict(formulation=args.formulation, linear_solver=args.linear_solver, convex=args.convex,
                          torsion_free_beams={"auto": "auto", "on": True, "off": False}[args.torsion_free_beams])))
    routes = []
    with _progress(args) as callback:
        if args.remesh == "never" or args.target == "strip":
            res = optimize_mesh(mesh, args.target, reference=reference, callback=callback, **kwargs)
        else:
            from optimize.remesh.routes import optimize_routes

            chosen, routes = optimize_routes(mesh, args.target, remesh=args.remesh, reference=reference, **kwargs)
            res = chosen.result
    write_mesh(args.output, to_file_units(res.mesh, args.units), comments=_marks(res))
    d = res.defects
    print(f"{mesh.name} -> {args.output}: {res.status} after {res.nit} iterations "
          f"({res.timings.get('total', 0.0):.2f} s, {res.method}/{res.target})")
    for key in TARGET_MEASURES[args.target]:  # the measures res.success was decided on (res.missed)
        if key in d:
            s = d[key]
            mark = "ok" if s.get("ok") else "NOT reached"
            mean = f"  mean {s['mean']:.3g}" if "mean" in s else ""
            print(f"  {key:10s} max {s['max']:.3g}{mean}  tolerance {s.get('tolerance')}  {mark}")
    for line in _other_defects(res, tol):
        print(line)
    dist, fair = d.get("distance"), d.get("fairness")
    diag = (reference or mesh).bbox_diagonal()
    if dist:
        print(f"  distance to the reference: max {dist['max']:.3g} mm of {diag:,.0f} mm diagonal "
              f"({100 * dist['max_relative']:.3g}%), mean {dist['mean']:.3g} mm ({100 * dist['mean_relative']:.3g}%)")
    else:
        print(f"  max distance to the reference: {res.max_distance:.3g} of the bbox diagonal "
              f"({res.max_distance * diag:.3g} mm of {diag:,.0f} mm)")
    if fair:
        print(f"  fairness (mean second difference / mean edge): input {fair['input']:.3g}, "
              f"result {fair['result']:.3g} (x{fair['ratio']:.2f})")
    fold = d.get("folded", {})
    print(f"  folded faces: {fold.get('count', 0)}" + (f" (first {fold['faces'][:5]})" if fold.get("count") else ""))
    short, straight = d.get("shrunk_edges", {}), d.get("straight_corners", {})
    print(f"  degenerate faces: {short.get('count', 0)} with a shrunk edge, {straight.get('count', 0)} with a "
          "straight corner" + "".join(f" (first {e['faces'][:5]})" for e in (short, straight) if e.get("count")))
    print(f"  {res.message}")
    for route in routes:
        print(f"  {route.line()}" + ("  <- written" if route.result is res else ""))
    if args.report:
        rep = {"input": str(args.mesh), "output": str(args.output), "units": args.units,
               "lengths": "mm", "tolerances": tol.as_dict(),
               "tolerance_reached": bool(res.success), **res.report()}
        if routes:
            rep["routes"] = [r.as_dict() for r in routes]
        with atomic_open(args.report) as fh:
            json.dump(rep, fh, indent=2)
    return 0 if res.success else 3


def _marks(res) -> list[str]:
    """Header comments of a written result that missed a tolerance (none for a success)."""
    if res is None or res.success:
        return []
    return [f"NOT CONVERGED: {res.target} {res.status} after {res.nit} iterations: {res.message}"]


OTHER = {"node_cone": ("node axes", "conical", "cone defect at vertices that are not interior valence 4 "
                                               "(irregular, boundary)"),
         "beam": ("beams", "conical", "planarity of the beams (torsion-free beams)"),
         "glide": ("glide", "planarity", "distance of gliding vertices to the boundary / mean edge"),
         "short_edge": ("short edges", "planarity", "edges at gliding vertices below their floor / mean edge")}


def _other_defects(res, tol) -> list[str]:
    """The solver's own defects beyond planarity/conical/circular (from its last iteration), so that
    the 'worst defect' of the message is printed too, with what it measures."""
    last = res.history[-1] if res.history else {}
    out = []
    for key, (label, limit, what) in OTHER.items():
        value = last.get(key)
        if not isinstance(value, float):
            continue
        t = getattr(tol, limit)
        mark = "ok" if value <= t else "NOT reached"
        out.append(f"  {label:10s} max {value:.3g}  mean {last.get(key + '_mean', float('nan')):.3g}  "
                   f"tolerance {t}  {mark}  ({what})")
    return out


class _progress:
    """Context manager giving the optimizer's ``callback``: a rich progress row on stderr
    (``--progress on``, or ``auto`` on a terminal), else None."""

    def __init__(self, args):
        on = args.progress == "on" or (args.progress == "auto" and sys.stderr.isatty())
        self.bar = None
        self.total = int(args.max_iter)
        self.note = ""
        if on:
            from ..progress import RichProgress

            self.bar = RichProgress(("optimize",), title=f"optimize {args.mesh} -> {args.output} "
                                                         f"({args.target})")

    def __enter__(self):
        if self.bar is None:
            return None
        self.bar.__enter__()
        self.bar.start("optimize", total=self.total)
        return self.callback

    def callback(self, entry: dict) -> None:
        figures = ", ".join(f"{k} {entry[k]:.2e}" for k in ("planarity", "conical", "circular", "node_cone")
                            if isinstance(entry.get(k), float))
        self.note = f"iteration {entry.get('iteration', '?')}: {figures}"
        self.bar.advance("optimize", 1, self.note)

    def __exit__(self, *exc):
        if self.bar is not None:
            self.bar.done("optimize", self.note)
            self.bar.__exit__(*exc)
        return None
