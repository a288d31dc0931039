"""Mesh file speed: write and read a ~100k-quad mesh in every format.

Prints seconds (wall; CPU in brackets, steadier on a shared machine) and the
ratio to a baseline measured in the same run (of CPU time): reading
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

from optimize.modelling import shapes  # noqa: E402
from optimize.mesh.io import read_mesh, write_mesh  # noqa: E402
from optimize.mesh.io.ply import format_ply  # noqa: E402


def _best(fn, repeat: int = 3) -> tuple[float, float]:
    """(wall, cpu) seconds, best of ``repeat``."""
    wall = cpu = np.inf
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        fn()
        wall, cpu = min(wall, time.perf_counter() - t), min(cpu, time.process_time() - c)
    return wall, cpu


def _row(label: str, t: tuple[float, float], base: float) -> str:
    return f"{label:42s} {t[0]:7.3f} s ({t[1]:6.3f}) {t[1] / base:5.2f}"


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

        tb = _best(baseline)
        base = tb[1]
        print(_row("baseline: split + float all OBJ tokens", tb, base))
        cases = [("obj", {}), ("off", {}), ("ply", {}), ("ply", {"binary": False})]
        for ext, kw in cases:
            path = Path(tmp) / f"m_{len(kw)}.{ext}"
            label = f"{ext}{' ascii' if kw else (' binary' if ext == 'ply' else '')}"
            tw = _best(lambda p=path, k=kw: write_mesh(p, mesh, **k))
            tr = _best(lambda p=path: read_mesh(p))
            assert np.array_equal(read_mesh(path).V, mesh.V)
            print(_row("write " + label, tw, base))
            print(_row("read " + label, tr, base))
        be = Path(tmp) / "be.ply"
        be.write_bytes(format_ply(mesh, "binary_big_endian"))
        print(_row("read ply binary big-endian", _best(lambda: read_mesh(be)), base))
        tris = mesh.V[mesh.triangulate()]  # STL: the triangle soup, corners welded on reading
        text = ["solid bench"]
        for t in tris.tolist():
            text += ["facet normal 0 0 1", "outer loop", *("vertex %r %r %r" % tuple(v) for v in t),
                     "endloop", "endfacet"]
        stl = Path(tmp) / "a.stl"
        stl.write_text("\n".join(text + ["endsolid bench"]) + "\n")
        print(_row(f"read stl ascii ({len(tris)} facets)", _best(lambda: read_mesh(stl)), base))
        rec = np.zeros(len(tris), dtype=[("n", "<f4", 3), ("v", "<f4", 9), ("a", "<u2")])
        rec["v"] = tris.reshape(-1, 9)
        stlb = Path(tmp) / "b.stl"
        stlb.write_bytes(b"bench".ljust(80) + np.uint32(len(tris)).tobytes() + rec.tobytes())
        print(_row("read stl binary", _best(lambda: read_mesh(stlb)), base))


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 317)
