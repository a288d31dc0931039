"""The sparse linear-solver backends of the default optimizer on one regularized
Gauss-Newton system each (``bench_optimize.py --linalg``): time of a fresh factorization and
solve per backend and the largest difference to the first backend's solution."""
from __future__ import annotations

import time

import numpy as np
from _optimize_cases import height_field, revolution


def linalg(args):
    import scipy.sparse as sp

    from optimize.linalg import BACKENDS, NormalSolver
    from optimize.mesh.measures import normalization
    from optimize.solvers.guided import _embed
    from optimize.terms.fairness import fairness_matrix_parts
    from optimize.terms.formulation import Formulation

    print("\nOne regularized Gauss-Newton system (first iteration), each backend, fresh factorization")
    print("(pardiso: analysis + numeric factorization + solve; the analysis is reused by later iterations):")
    for mesh, target, unknowns in ((height_field(10000), "pq", "auxiliary"),
                                   (revolution(10000), "circular", "auxiliary"),
                                   (revolution(10000), "conical", "auxiliary"),
                                   (revolution(10000), "conical", "vertices")):
        c, h = normalization(mesh)
        nm = mesh.with_vertices((mesh.V - c) / h)
        form = Formulation(nm, target, unknowns)
        x = form.start(nm.V)
        r, J = form.terms(x)
        K1, K2 = (_embed(k, J.shape[1]) for k in fairness_matrix_parts(nm))
        A = (J.T @ J + 2e-3 * (K1.T @ K1 + K2.T @ K2) + 1e-3 * sp.eye(J.shape[1])).tocsr()
        b = -(J.T @ r)
        line = f"{mesh.name:14s} {target:8s} {unknowns:9s} unknowns {A.shape[0]:7d} nnz {A.nnz:8d}:"
        ref = None
        for be in BACKENDS:
            if be == "auto" or (be == "eliminate" and form.face_blocks() is None):
                continue
            s = NormalSolver(be, form.face_blocks(), reuse=False)
            t = time.perf_counter()
            xs = s.solve(A, b)
            line += f"  {be} {time.perf_counter() - t:6.2f} s"
            if be == "pardiso":
                sec = s._pardiso.seconds
                line += f" [{sec['analysis']:.2f}+{sec['numeric']:.2f}+{sec['solve']:.2f}, L {s._pardiso.factor_nnz / 1e6:.1f}M]"
            ref = xs if ref is None else ref
            line += f" (diff {np.abs(xs - ref).max():.0e})"
        print(line)
