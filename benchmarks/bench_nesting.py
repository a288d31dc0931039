"""Nesting on the bench's dome: the compiled kernel against the Python path, same placements.

Builds the dome of ``--panels`` panels with RHS beams welded from plates, tube hubs and insulated glass
(``bench_cad``'s ``rhs`` variant), then times, per path, ``layout(parts)`` (every flat part on one
drawing strip, as outlines.dxf) and ``nest_cut_files`` (per material and thickness on stock sheets),
``--repeat`` times each, and checks that both paths give the same layouts (sheet, x, y, turn of every
part).  The kernel's load (numba import and disk cache, or the first compile) is printed apart.

    python benchmarks/bench_nesting.py                # 5,000 panels
    python benchmarks/bench_nesting.py --panels 500   # quick

On a shared machine the timings are noisy: take the best of the repetitions.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--panels", type=int, default=5000)
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args(argv)
    import bench_cad
    from fabricate.app.config import NestingSection
    from fabricate.cad import PartSpec, build_parts
    from fabricate.export import nesting
    from fabricate.export.cutfiles import nest_cut_files
    from optimize import kernels

    parts = build_parts(bench_cad.structure(args.panels), PartSpec(beam_width=80.0, **bench_cad.spec_keywords("rhs")))
    t = time.perf_counter()
    kernel = nesting._kernel()
    if kernel is not None:
        kernel.pack_bins(np.array([2], np.int64), np.array([1], np.int64), np.array([0]), 4, 4, True, False)
    print(f"parts {len(parts)}; kernel: " + ("numba missing or switched off" if kernel is None else
                                            f"loaded (or compiled) in {time.perf_counter() - t:.2f} s"))
    best: dict = {}
    layouts: dict = {}
    for enabled in (True, False) * args.repeat:
        kernels.ENABLED = enabled                 # the compiled kernels' switch (CONICAL_FAB_NUMBA)
        nesting._LAYOUTS.clear()
        t = time.perf_counter()
        strip = nesting.layout(parts)
        t1 = time.perf_counter()
        batches = nest_cut_files(parts, NestingSection().model_dump())
        t2 = time.perf_counter()
        mode = "kernel" if enabled and kernel is not None else "python"
        old = best.get(mode, (np.inf, np.inf))
        best[mode] = (min(old[0], t1 - t), min(old[1], t2 - t1))
        layouts[mode] = [strip] + [b["layout"] for b in batches]
    for mode, (a, b) in best.items():
        print(f"{mode:7s} layout(parts) {a:.3f} s   nest_cut_files {b:.3f} s   (best of {args.repeat})")
    if len(layouts) == 2:
        for p, q in zip(layouts["kernel"], layouts["python"]):
            assert p.ids == q.ids and p.sheets == q.sheets and p.size == q.size
            for name in ("sheet", "x", "y", "rotated", "utilisation"):
                assert np.array_equal(getattr(p, name), getattr(q, name)), name
        print(f"same placements: {sum(len(p.ids) for p in layouts['kernel'])} parts in {len(layouts['kernel'])} layouts")


if __name__ == "__main__":
    main()
