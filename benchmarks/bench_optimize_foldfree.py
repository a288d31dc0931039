"""The fold-free table of ``bench_optimize.py`` (``--foldfree-only``): on wave900, hypar900,
conjugate900+noise, a skew torus, a blob and the ``--data DIR`` meshes, the new default
(``ours``), the old one (``ours-old``: ``convex=False``, the fairness weight in full), the
remeshed route (``ours+rm``), the paper's methods and libigl / mpfp, each with its fold
count and distance; ratios are time / the new default's, measured in the same run."""
from __future__ import annotations

import time

import _optimize_cases as bench_cases
from _optimize_cases import (
    blob,
    cylinder,
    halftunnel,
    height_field,
    print_table,
    result_row,
    skew_torus,
)
from _optimize_peers import ensure, run_libigl, run_mpfp

from optimize import optimize_mesh
from optimize.modelling import shapes


def foldfree_table(args):
    """Old (no convexity rows, fairness weight in full) and new default, the paper's methods,
    the remeshed route and libigl / mpfp where installed, with folds and distances."""
    from optimize.mesh.conjugacy import net_defect
    from optimize.remesh.routes import optimize_routes
    from optimize.solvers import guided

    igl = mpfp = None
    if not args.no_peers:
        igl = ensure("igl", "libigl", not args.no_install)
        mpfp = ensure("mpfp", "mpfp", not args.no_install)
    cases = [(height_field(900), "pq"), (height_field(900, "hypar"), "pq"), (height_field(900, "conjugate"), "pq"),
             (skew_torus(), "pq"), (blob(), "pq"), (blob(), "conical")]
    if bench_cases.DATA is not None:
        cases += [(halftunnel(), "pq"), (halftunnel(), "conical"), (halftunnel(), "circular"), (cylinder(), "pq")]
    print("\nFold-free table: 'fold' = faces convex in the input, dented / flipped / collapsed in the result;")
    print("'dist' = max distance to the input surface in % of its bbox diagonal; ratio = time / new default")
    warm = shapes.perturbed(shapes.grid(6, 6, height=lambda x, y: 0.1 * x * y), 0.05, seed=0)
    optimize_mesh(warm, "pq")
    rows = []
    for mesh, target in cases:
        net = net_defect(mesh)
        print(f"\n{mesh.name} {target}: {net.line(target)}")
        t = time.perf_counter()
        res = optimize_mesh(mesh, target)
        new_t = time.perf_counter() - t
        group = [result_row(mesh, mesh.name, target, "ours", new_t, res)]
        far, guided.FAR = guided.FAR, None
        try:
            t = time.perf_counter()
            old = optimize_mesh(mesh, target, convex=False)
            group.append(result_row(mesh, mesh.name, target, "ours-old", time.perf_counter() - t, old))
        finally:
            guided.FAR = far
        t = time.perf_counter()
        chosen, routes = optimize_routes(mesh, target, remesh="always", original=res)
        if len(routes) > 1 and routes[1].result is not None:
            group.append(result_row(mesh, mesh.name, target, "ours+rm", routes[1].seconds, routes[1].result))
        elif len(routes) > 1:
            group[0]["note"] = routes[1].note[:60]
        for method in args.paper_methods:
            if mesh.n_faces > args.paper_max_faces:
                continue
            t = time.perf_counter()
            pr = optimize_mesh(mesh, target, method=method, max_iter=args.paper_iter)
            group.append(result_row(mesh, mesh.name, target, method, time.perf_counter() - t, pr))
        if target == "pq":
            for pname, lib, fn in (("libigl", igl, run_libigl), ("mpfp", mpfp, run_mpfp)):
                if lib is not None:
                    p = fn(lib, mesh, args.peer_budget)
                    group.append(p)
        for r in group[1:]:
            r["ratio"] = f"time x{r['seconds'] / max(new_t, 1e-9):.2f}"
        print_table(group, percent=True)
        rows += group
    return rows
