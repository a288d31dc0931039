"""Mesh file speed: write and read a ~100k-quad mesh in every format.

Prints seconds and the ratio to a baseline measured in the same run: reading
the OBJ text and converting every whitespace token to a float in one numpy
call (the floor of any Python text parser; the real reader also keeps line
numbers, resolves indices and validates the mesh).

    python benchmarks/bench_io.py [N]      # N x N vertex grid, default 317 (~100k quads)
"""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # this checkout, not an installed copy

from optimize import shapes  # noqa: E402
from optimize.io import read_mesh, write_mesh  # noqa: E402
from optimize.io.ply import format_ply  # noqa: E402


def _best(fn, repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def main(n: int = 317) -> None:
    mesh = shapes.grid(n, n, height=lambda x, y: np.sin(3 * x) * np.cos(2 * y), name="bench")
    print(f"{mesh.n_vertices} vertices, {mesh.n_faces} quads; best of 3 (timings on a shared "
          "machine are noisy)")
    with tempfile.TemporaryDirectory() as tmp:
        obj = Path(tmp) / "m.obj"
        write_mesh(obj, mesh)

        def baseline():
            text = obj.read_text().split("\n", 1)[1]  # after the comment line
            np.array(text.replace("v", " ").replace("f", " ").split(), dtype=np.float64)

        base = _best(baseline)
        print(f"{'baseline: split + float all OBJ tokens':42s} {base:7.3f} s   1.00")
        cases = [("obj", {}), ("off", {}), ("ply", {}), ("ply", {"binary": False})]
        for ext, kw in cases:
            path = Path(tmp) / f"m_{len(kw)}.{ext}"
            label = f"{ext}{' ascii' if kw else (' binary' if ext == 'ply' else '')}"
            tw = _best(lambda p=path, k=kw: write_mesh(p, mesh, **k))
            tr = _best(lambda p=path: read_mesh(p))
            assert np.array_equal(read_mesh(path).V, mesh.V)
            print(f"{'write ' + label:42s} {tw:7.3f} s {tw / base:5.2f}")
            print(f"{'read ' + label:42s} {tr:7.3f} s {tr / base:5.2f}")
        be = Path(tmp) / "be.ply"
        be.write_bytes(format_ply(mesh, "binary_big_endian"))
        tr = _best(lambda: read_mesh(be))
        print(f"{'read ply binary big-endian':42s} {tr:7.3f} s {tr / base:5.2f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 317)
