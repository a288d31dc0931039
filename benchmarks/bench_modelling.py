"""The paper's two modelling timings, reproduced and printed beside the paper's figures.

1. PQ perturbation of the 336-face trefoil band (Liu et al. 2006, Fig. 9:
   0.08 s penalty, 0.75 s SQP on a 2 GHz PC): the built-in ``trefoil_band``
   refined twice with perturbation, refined a third time (336 quads), then
   perturbed to the strip target by each of the paper's methods, and to PQ by
   the default solver (an in-run peer).
2. The conical level of a ~6,000-vertex design (paper Fig. 14: about 10 s
   of a 13 s total): ``railway_station(nu=15, nv=6)``, three Catmull-Clark
   levels (5,929 vertices at the last), the last level timed on its own and
   the whole hierarchy too; ``--paper`` also runs the paper's penalty method
   on that level as an in-run peer (slow).

Each timing is the best of ``--repeat`` runs (the machine is shared; figures
are noisy).  The ratio is paper seconds / our seconds (goal: >= 10).  The
paper's figures come from a 2006 PC, so the ratio compares machines as well
as methods; the in-run peers compare methods on this machine.

    python benchmarks/bench_modelling.py [--repeat 3] [--paper]
"""
from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout, not an installed copy

from optimize.api import optimize_mesh  # noqa: E402
from optimize.modelling.designs import DESIGNS  # noqa: E402
from optimize.modelling.hierarchy import subdivide_and_perturb  # noqa: E402
from optimize.modelling.subdivision import subdivide  # noqa: E402

PAPER = {"trefoil penalty": 0.08, "trefoil sqp": 0.75, "conical level": 10.0, "conical total": 13.0}


def _best(fn, repeat: int):
    best, out = float("inf"), None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def _row(label: str, seconds: float, result, paper: float | None) -> None:
    d = result.defects
    plan = d["planarity"]["max"]
    con = d["conical"]["max"] if result.target == "conical" else float("nan")
    ratio = f"{paper / seconds:7.1f}x" if paper else "       "
    pap = f"{paper:6.2f} s" if paper else "        "
    print(f"{label:34s} {seconds:8.3f} s  {pap}  {ratio}  {result.status:9s} {result.nit:4d} it  "
          f"planarity {plan:8.1e}  conical {con:8.1e}  dist {result.max_distance:7.1e}"
          + (f"  energy {result.history[-1]['energy']:.1e}" if "energy" in (result.history or [{}])[-1] else ""))


def trefoil(repeat: int) -> None:
    from optimize import kernels

    compile_s = kernels.warm_up()  # numba: compiled or loaded from its disk cache, not counted below
    d = DESIGNS["trefoil_band"]()
    prev = subdivide_and_perturb(d.mesh, 2, scheme=d.scheme, target=d.target).mesh
    band, _ = subdivide(prev, d.scheme, 1)
    print(f"\ntrefoil band: {band.n_faces} quads (Moebius), perturbation of the third refinement")
    print("numba kernels of the paper's methods: " + ("not available (NumPy paths)" if kernels.get() is None
          else f"ready in {compile_s:.3f} s (not counted)") + "; 'first' = first run on this mesh "
          "(builds the problem that later runs reuse)")
    print(f"{'case':34s} {'ours':>10s}  {'paper':>8s}  {'ratio':>8s}  status")
    for method, key in (("penalty", "trefoil penalty"), ("sqp", "trefoil sqp"), ("hybrid", None)):
        t0 = time.perf_counter()
        optimize_mesh(band, "strip", method=method, reference=band)
        first = time.perf_counter() - t0
        sec, res = _best(lambda m=method: optimize_mesh(band, "strip", method=m, reference=band), repeat)
        _row(f"strip, paper {method}", sec, res, PAPER.get(key))
        print(f"{'':34s} (first run {first:.3f} s)")
    sec, res = _best(lambda: optimize_mesh(band, "pq", reference=band), repeat)
    _row("pq, default solver (peer)", sec, res, PAPER["trefoil penalty"])


def conical(repeat: int, paper_methods: bool) -> None:
    d = DESIGNS["railway_station"](nu=15, nv=6)
    t0 = time.perf_counter()
    run = subdivide_and_perturb(d.mesh, 3, scheme=d.scheme, target="conical")
    total = time.perf_counter() - t0
    last = run.levels[-1]
    print(f"\nrailway_station 15 x 6: levels {[lv.mesh.n_vertices for lv in run.levels]} vertices, "
          f"conical at every level")
    print(f"{'case':34s} {'ours':>10s}  {'paper':>8s}  {'ratio':>8s}  status")
    for lv in run.levels:
        _row(f"level {lv.level} ({lv.mesh.n_vertices} v), in hierarchy", lv.seconds["optimize"], lv.result,
             PAPER["conical level"] if lv.level == 3 else None)
    ref = last.reference
    sec, res = _best(lambda: optimize_mesh(ref, "conical", reference=ref), repeat)
    _row(f"level 3 alone ({ref.n_vertices} v)", sec, res, PAPER["conical level"])
    print(f"{'whole hierarchy (3 levels)':34s} {total:8.3f} s  {PAPER['conical total']:6.2f} s  "
          f"{PAPER['conical total'] / total:7.1f}x  success={run.success}")
    if paper_methods:
        sec, res = _best(lambda: optimize_mesh(ref, "conical", method="penalty", reference=ref), 1)
        _row("level 3, paper penalty (peer)", sec, res, PAPER["conical level"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="best of this many runs (default 3)")
    ap.add_argument("--paper", action="store_true", help="also time the paper's penalty method on "
                                                         "the 6,000-vertex conical level (slow)")
    args = ap.parse_args()
    logging.basicConfig(level=logging.WARNING)
    print("Paper figures: 2 GHz PC, 2006. Ours: this machine, best of "
          f"{args.repeat}, shared by other jobs (noisy). ratio = paper / ours, goal >= 10x.")
    trefoil(args.repeat)
    conical(args.repeat, args.paper)


if __name__ == "__main__":
    main()
