"""The peers of the PQ benchmarks: libigl's ``planarize_quad_mesh`` and mpfp's
``make_planar_faces``, installed with pip for the benchmark run only when missing
(not dependencies of the project), each run on an iteration budget in seconds."""
from __future__ import annotations

import importlib
import subprocess
import sys
import time

import numpy as np
from _optimize_cases import row

from optimize.mesh import measures


def ensure(module, package, allow):
    try:
        return importlib.import_module(module)
    except ImportError:
        if not allow:
            return None
        subprocess.run([sys.executable, "-m", "pip", "install", "-q", package], check=False)
        try:
            return importlib.import_module(module)
        except ImportError:
            return None


def run_libigl(igl, mesh, budget):
    V, F = np.ascontiguousarray(mesh.V), np.ascontiguousarray(mesh.F)
    t = time.perf_counter()
    V1 = igl.planarize_quad_mesh(V, F, 1, 1e-6)
    first = time.perf_counter() - t
    iters = int(max(1, min(2000, budget / max(first, 1e-3))))
    t = time.perf_counter()
    Vout = igl.planarize_quad_mesh(V, F, iters, 1e-6)
    r = row(mesh, mesh.name, "pq", "libigl", time.perf_counter() - t, Vout, iters)
    r["note"] = f"budget {iters} iterations"
    del V1
    return r


def libigl_time_to(igl, mesh, threshold, budget):
    """Seconds libigl takes to bring the max planarity to ``threshold``, continuing its
    iteration in chunks (its state is the vertex array alone) until reached or ``budget``
    seconds are spent; the planarity is measured between chunks, outside the clock."""
    V, F = np.ascontiguousarray(mesh.V), np.ascontiguousarray(mesh.F)
    spent, iters, chunk = 0.0, 0, 25
    while spent < budget:
        t = time.perf_counter()
        V = igl.planarize_quad_mesh(V, F, chunk, 1e-12)
        spent += time.perf_counter() - t
        iters += chunk
        worst = float(measures.planarity(mesh.with_vertices(np.asarray(V))).max())
        if worst <= threshold:
            return spent, iters, worst
    return None, iters, worst


def run_mpfp(mpfp, mesh, budget):
    s = mpfp.MakePlanarSettings()
    s.verbose = False
    s.optimization_rounds = 1
    t = time.perf_counter()
    mpfp.make_planar_faces(list(mesh.V), mesh.faces_list(), [], s)
    first = time.perf_counter() - t
    s.optimization_rounds = int(max(1, min(50, budget / max(first, 1e-3))))
    t = time.perf_counter()
    out = mpfp.make_planar_faces(list(mesh.V), mesh.faces_list(), [], s)
    r = row(mesh, mesh.name, "pq", "mpfp", time.perf_counter() - t, np.array(out).reshape(-1, 3),
            s.optimization_rounds)
    r["note"] = f"budget {s.optimization_rounds} rounds"
    return r
