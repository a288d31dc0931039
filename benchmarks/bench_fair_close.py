"""Exact, fair and close (#31 item 1-2): the default optimizer against its variants, per case.

Prints, per mesh, target and variant: status, iterations, max distance to the input surface
in % of its bbox diagonal, roughness ratio (result / input, ``fairness.roughness``), folded
faces and seconds, every variant measured in the same run.

Variants: ``plain`` (the guided solve alone, ``refine=False``), ``default`` (as shipped: the
constrained fairing phase of :mod:`optimize.solvers.fairing` when the result moved further than
the closeness tolerance, ``refine="auto"``), ``fairing`` (the phase always, ``refine=True``),
``far-off`` (no phase, the fairness weight not scaled by the defect, ``guided.FAR = None``) and
``fairing-far-off`` (both).

Cases: the two COMPAS roofs and the tunnel of ``configs/meshes`` (metres), a noisy height-field
canopy, a noisy translational vault (a conjugate net: PQ exactly before the noise) and, with
``--halftunnel PATH``, libigl's halftunnel.

    .venv/bin/python benchmarks/bench_fair_close.py [--halftunnel PATH] [--only NAME] [--targets pq,conical]
"""
from __future__ import annotations

import argparse
import contextlib
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from optimize import optimize_mesh  # noqa: E402
from optimize.mesh.io import read_mesh  # noqa: E402
from optimize.modelling import shapes  # noqa: E402
from optimize.solvers import guided  # noqa: E402

MESHES = ROOT / "configs" / "meshes"


def canopy(n: int = 12):
    """A height-field canopy 12 x 8 m, two bumps, seeded noise of 5% of the edge length."""
    height = lambda x, y: (1.2 * np.exp(-((x - 4) ** 2 + (y - 4) ** 2) / 6)  # noqa: E731
                           + 0.8 * np.exp(-((x - 8.5) ** 2 + (y - 3.5) ** 2) / 4))
    mesh = shapes.grid(n, n, size=(12.0, 8.0), height=height, name=f"canopy{(n - 1) ** 2}")
    return shapes.perturbed(mesh, 0.05, seed=3, name=mesh.name + "+noise")


def vault(n: int = 12):
    """A translational vault ``z = f(x) + g(y)`` (its grid lines a conjugate net: PQ exactly),
    10 x 8 m, with seeded noise of 5% of the edge length."""
    height = lambda x, y: 2.0 - 0.08 * (x - 5) ** 2 - 0.05 * (y - 4) ** 2  # noqa: E731
    mesh = shapes.grid(n, n, size=(10.0, 8.0), height=height, name=f"vault{(n - 1) ** 2}")
    return shapes.perturbed(mesh, 0.05, seed=4, name=mesh.name + "+noise")


def design_canopy():
    """The shipped ``freeform_canopy`` design (30 x 20 m, two bumps) subdivided once (Catmull-Clark):
    smooth, its grid lines neither conjugate nor principal."""
    from optimize.modelling.designs import freeform_canopy
    from optimize.modelling.subdivision import catmull_clark

    mesh, _ = catmull_clark(freeform_canopy().mesh, 1)
    return mesh


@contextlib.contextmanager
def variant(name: str):
    """Module settings of one variant, restored afterwards."""
    saved = guided.FAR
    try:
        if name in ("plain", "default"):  # plain: no fairing phase; default: the package's (refine: auto)
            yield {"refine": False} if name == "plain" else {}
        elif name == "far-off":
            guided.FAR = None
            yield {"refine": False}
        elif name == "fairing":
            yield {"refine": True}
        elif name == "fairing-far-off":
            guided.FAR = None
            yield {"refine": True}
        else:
            raise ValueError(name)
    finally:
        guided.FAR = saved


def one(mesh, target: str, name: str) -> dict:
    with variant(name) as kw:
        t = time.perf_counter()
        res = optimize_mesh(mesh, target, **kw)
        sec = time.perf_counter() - t
    d = res.defects
    return {"status": res.status, "nit": res.nit, "dist": 100 * d["distance"]["max_relative"],
            "rough": d["fairness"]["ratio"], "folded": d["folded"]["count"], "seconds": sec,
            "defect": float(max(v for k, v in (res.history[-1] if res.history else {}).items()
                                if k in ("planarity", "conical", "circular")) if res.history else 0.0)}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--halftunnel", help="path of halftunnel.off (libigl's tutorial data)")
    ap.add_argument("--only", help="run only meshes whose name contains this")
    ap.add_argument("--targets", default="pq,conical,circular")
    ap.add_argument("--variants", default="plain,default,fairing,far-off")
    args = ap.parse_args(argv)
    cases = [read_mesh(MESHES / "compas_quadmesh.obj"), read_mesh(MESHES / "compas_tubemesh.obj"),
             read_mesh(MESHES / "tunnel.off"), canopy(), vault(), design_canopy()]
    if args.halftunnel:
        cases.append(read_mesh(args.halftunnel))
    if args.only:
        cases = [m for m in cases if args.only in m.name]
    optimize_mesh(shapes.perturbed(shapes.grid(5, 5, height=lambda x, y: 0.1 * x * y), 0.05, seed=0), "pq")
    print(f"{'mesh':22s} {'target':8s} {'variant':11s} {'status':10s} {'nit':>4s} {'dist %':>7s} "
          f"{'rough x':>7s} {'fold':>4s} {'sec':>6s}")
    for mesh in cases:
        for target in args.targets.split(","):
            for name in args.variants.split(","):
                try:
                    r = one(mesh, target, name)
                except Exception as exc:  # a benchmark row, not a crash of the table
                    print(f"{Path(mesh.name).stem[:22]:22s} {target:8s} {name:11s} error: {exc}"[:160], flush=True)
                    continue
                print(f"{Path(mesh.name).stem[:22]:22s} {target:8s} {name:11s} {r['status']:10s} {r['nit']:4d} "
                      f"{r['dist']:7.3f} {r['rough']:7.2f} {r['folded']:4d} {r['seconds']:6.1f}", flush=True)


if __name__ == "__main__":
    main()
