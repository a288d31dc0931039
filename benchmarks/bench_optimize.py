"""Benchmark of the default optimizer against libigl and mpfp, measured in the same run.

    python benchmarks/bench_optimize.py              # table + PQ scaling curve to 30k faces
    python benchmarks/bench_optimize.py --foldfree-only --data DIR   # folds, old vs new; DIR: extra meshes
    python benchmarks/bench_optimize.py --large      # scaling curve up to 100k faces
    python benchmarks/bench_optimize.py --linalg     # the sparse solver backends on one system
    python benchmarks/bench_optimize.py --no-peers   # ours only

The peers (``libigl.planarize_quad_mesh``, ``mpfp.make_planar_faces``) are
installed with pip for the benchmark run only when missing (``--no-install``
to forbid); they are not dependencies of the project.  Each peer gets an
iteration budget (``--peer-budget`` seconds, estimated from its first
iteration) so a run ends; a peer that does not reach the tolerance is shown
with the defect it reached.  Rows ``ours-slu`` (SciPy SuperLU), ``ours-aux``
(auxiliary unknowns) and ``ours-nax`` (no node axes: on an irregular mesh the
beams at its irregular nodes twist) are our previous defaults, timed in the
same run.  Ratios are peer time / our time (bigger is
better for us).  Timings on a shared 2-core machine are noisy.

Columns: mesh, faces, target, method, seconds, final max and mean defect
(planarity, or the target's angle defect), max distance to the input surface
in % of its bbox diagonal, iterations, faces folded (convex in the input,
dented, flipped or collapsed in the output: planar but not cuttable; every
method's status then says ``folded``), and the ratio to each peer.

The fold-free table (first; ``--foldfree-only``) runs, on wave900, hypar900,
conjugate900+noise, a skew torus and a blob (closed, their mesh lines not
conjugate) and extra real meshes (``--data DIR``): the new default
(``ours``: convexity rows, fairness weight falling with the defect), the old
one (``ours-old``: ``convex=False`` and the fairness weight in full), the
remeshed route (``ours+rm``: ``optimize.remesh.routes``, remeshed along principal
directions; closed meshes cannot be remeshed), the paper's penalty / SQP /
hybrid and libigl / mpfp, each with its fold count and distance.
The scaling curve runs every size in a fresh process and reports its peak
resident memory.

Modules: this one the comparison table and the command line;
``bench_optimize_foldfree.py`` the fold-free table, ``bench_optimize_scaling.py`` the
scaling curve, ``bench_optimize_linalg.py`` the linear-solver backends;
``_optimize_cases.py`` the meshes and rows, ``_optimize_peers.py`` libigl and mpfp.
"""
from __future__ import annotations

import argparse
import time

import _optimize_cases as bench_cases
from _optimize_cases import (
    halftunnel,
    height_field,
    ours,
    print_table,
    real_mesh,
    revolution,
)
from _optimize_peers import ensure, libigl_time_to, run_libigl, run_mpfp

from optimize import optimize_mesh
from optimize.modelling import shapes


def comparison(args):
    igl = mpfp = None
    if not args.no_peers:
        igl = ensure("igl", "libigl", not args.no_install)
        mpfp = ensure("mpfp", "mpfp", not args.no_install)
    shared = [(halftunnel(), "pq"), (halftunnel(), "conical"), (halftunnel(), "circular")] if bench_cases.DATA else []
    cases = [(height_field(900, "conjugate"), "pq"), (height_field(900), "pq"), (height_field(900, "hypar"), "pq"),
             (real_mesh(args.mesh), "pq"), (real_mesh(args.mesh), "conical"), (real_mesh(args.mesh), "circular"),
             *shared, (revolution(10000), "pq"), (revolution(10000), "conical"), (revolution(2500), "circular"),
             (height_field(10000), "pq")]
    if args.quick:
        cases = cases[:6 + len(shared)]
    # one-time costs (MKL and OpenMP start-up, first sparse factorizations) outside the clock
    warm = shapes.perturbed(shapes.grid(6, 6, height=lambda x, y: 0.1 * x * x), 0.05, seed=0)
    for kw in ({}, {"linear_solver": "superlu"}):
        optimize_mesh(warm, "conical", **kw)
    rows = []
    for mesh, target in cases:
        r = ours(mesh, target)
        rows.append(r)
        # in-run baselines of our own: the previous defaults (SciPy SuperLU; for conical the
        # auxiliary-variable formulation) on the same mesh
        t = mesh.topology
        irregular = bool(t.interior_irregular.size)
        base = [("ours-aux", dict(formulation="auxiliary"))] if target == "conical" else []
        if target == "conical" and irregular:  # nax: no node axes (cones at valence 4 only, beams twist)
            base.append(("ours-nax", dict(torsion_free_beams=False)))
        if not (target == "conical" and mesh.n_faces > 3000):  # SuperLU on aux conical 10k: ~270 s
            base.append(("ours-slu", dict(linear_solver="superlu",
                                          formulation="auxiliary" if target == "conical" else "auto")))
        own = []
        for label, kw in base:
            b = ours(mesh, target, **kw)
            b["method"] = label
            b["ratio"] = f"time / ours x{b['seconds'] / r['seconds']:.2f}"
            rows.append(b)
            own.append(b)
        if target != "pq":
            print_table([r] + own)
            print(flush=True)
            continue
        ratios, peers = [], []
        for name, lib, fn in (("libigl", igl, run_libigl), ("mpfp", mpfp, run_mpfp)):
            if lib is None or (name == "mpfp" and mesh.n_faces > 3000 and not args.full):
                continue
            p = fn(lib, mesh, args.peer_budget)
            reached = p["max"] <= 1e-6
            p["note"] = (p["note"] + ("" if reached else ", did not reach 1e-6"))
            rows.append(p)
            peers.append(p)
            ratios.append(f"{name} x{p['seconds'] / r['seconds']:.1f}" + ("" if reached else " (peer unconverged)"))
        if igl is not None and mesh.n_faces <= 3000 and args.to_1e3:
            sec, iters, worst = libigl_time_to(igl, mesh, 1e-3, args.to_1e3)
            if sec is None:
                r["note"] = f"libigl did not reach 1e-3 in {args.to_1e3:.0f} s ({iters} it, {worst:.2e})"
            else:
                ratios.append(f"libigl to 1e-3 in {sec:.1f} s ({iters} it): x{sec / r['seconds']:.0f}")
        r["ratio"] = ", ".join(ratios)
        print_table([r] + own + peers)
        print(flush=True)
    print("\nAll rows (peer time / our time; 'max' is the target's defect):")
    print_table(rows)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="small cases only")
    ap.add_argument("--mesh", metavar="PATH", help="a quad mesh to use instead of configs/meshes/tunnel.off")
    ap.add_argument("--large", action="store_true", help="scaling curve up to 100k faces")
    ap.add_argument("--full", action="store_true", help="run mpfp on the large meshes too (minutes)")
    ap.add_argument("--no-peers", action="store_true")
    ap.add_argument("--no-install", action="store_true")
    ap.add_argument("--no-scaling", action="store_true")
    ap.add_argument("--scaling-only", action="store_true")
    ap.add_argument("--linalg", action="store_true", help="only the linear-solver comparison")
    ap.add_argument("--peer-budget", type=float, default=60.0, help="seconds per peer run (estimate)")
    ap.add_argument("--to-1e3", type=float, default=180.0, metavar="S",
                    help="seconds libigl may take to reach planarity 1e-3 on meshes up to 3k faces "
                         "(the issue's 100x goal is against that time; 0 to skip)")
    ap.add_argument("--data", metavar="DIR", help="folder with halftunnel.off and cylinder.obj "
                                                 "(e.g. from the libigl tutorial data): their rows too")
    ap.add_argument("--foldfree-only", action="store_true", help="only the fold-free table")
    ap.add_argument("--no-foldfree", action="store_true", help="skip the fold-free table")
    ap.add_argument("--paper-methods", nargs="*", default=["penalty", "sqp", "hybrid"],
                    help="the paper's methods in the fold-free table")
    ap.add_argument("--paper-max-faces", type=int, default=1000, help="meshes up to this size get paper rows")
    ap.add_argument("--paper-iter", type=int, default=200, help="iteration budget of the paper's methods")
    ap.add_argument("--one", nargs=2, metavar=("TARGET", "FACES"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    bench_cases.DATA = args.data
    if args.one:
        from bench_optimize_scaling import one
        return one(args.one[0], int(args.one[1]))
    if args.linalg:
        from bench_optimize_linalg import linalg
        return linalg(args)
    print(f"benchmark of the default optimizer; {time.strftime('%Y-%m-%d %H:%M')}; "
          "timings on a shared machine are noisy")
    if not args.scaling_only and not args.no_foldfree:
        from bench_optimize_foldfree import foldfree_table
        foldfree_table(args)
    if args.foldfree_only:
        return
    if not args.scaling_only:
        comparison(args)
    if not args.no_scaling:
        from bench_optimize_scaling import scaling
        scaling(args)


if __name__ == "__main__":
    main()
