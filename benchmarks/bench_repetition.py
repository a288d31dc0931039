"""Repetition (#37): shapes within 1 mm before and after, with the design's symmetry kept and with
``optimize.rationalize``; distance moved (mm, % of the diagonal) and seconds.

    .venv/bin/python benchmarks/bench_repetition.py [--no-railway]

Cases: the quickstart dome (12 x 3 quads, noise 0.02), a mirror-symmetric canopy (7 x 5 quads,
noisy but symmetric), the railway station at level 2 (640 panels; about 10-15 s per run).
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from optimize.api import optimize_mesh
from optimize.mesh import symmetry
from optimize.mesh.congruence import face_classes
from optimize.modelling import shapes
from optimize.modelling.designs import dome, railway_station
from optimize.modelling.hierarchy import subdivide_and_perturb
from optimize.modelling.subdivision import subdivide
from optimize.tolerances import Tolerances


def canopy():
    g = shapes.grid(8, 6, (7.0, 5.0), height=lambda x, y: 0.3 * ((x - 3.5) ** 2 - (y - 2.0) ** 2 / 2) / 4)
    g = g.with_vertices(g.V * 1000.0, name="canopy")
    noisy = shapes.perturbed(g, 0.04, seed=2)
    return noisy.with_vertices(symmetry.detect(g).symmetrize(noisy.V))


def row(name, res, design, seconds):
    diag = float(np.linalg.norm(np.ptp(design.V, axis=0)))
    from optimize.proximity.surface import Reference

    d = float(Reference(design).distance(res.mesh.V).max())
    rat = res.defects.get("rationalize") or {}
    sym = res.defects.get("symmetry") or {}
    before = rat.get("before", {}).get("shapes", "-")
    print(f"{name:34s} {res.mesh.n_faces:6d} {before!s:>7s} {face_classes(res.mesh).count:6d} "
          f"{sym.get('order', 1):5d} {d:9.1f} {100 * d / diag:7.3f} {res.defects['conical']['max']:9.1e} "
          f"{seconds:7.2f}  {rat.get('stop', '')}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--no-railway", action="store_true")
    ap.add_argument("--pull", type=float, default=100.0)
    a = ap.parse_args()
    print(f"{'case':34s} {'faces':>6s} {'before':>7s} {'shapes':>6s} {'group':>5s} {'moved mm':>9s} "
          f"{'% diag':>7s} {'conical':>9s} {'seconds':>7s}")
    q = dome(radius=6000, rise=2500, meridians=12, rings=4, noise=0.02, seed=1).mesh
    c = canopy()
    for name, mesh in (("quickstart dome", q), ("mirror canopy", c)):
        for pull in (None, a.pull):
            t = time.perf_counter()
            res = optimize_mesh(mesh, "conical", rationalize=pull)
            row(f"{name}, rationalize {pull}", res, mesh, time.perf_counter() - t)
    if not a.no_railway:
        d = railway_station(levels=2)
        design, _ = subdivide(d.mesh, "catmull_clark", 2)
        tol = Tolerances(planarity=1e-9, conical=1e-9)
        for pull in (None, 20.0):
            t = time.perf_counter()
            h = subdivide_and_perturb(d.mesh, 2, target="conical", tol=tol, rationalize=pull)
            row(f"railway station L2, rationalize {pull}", h.levels[-1].result, design, time.perf_counter() - t)


if __name__ == "__main__":
    main()
