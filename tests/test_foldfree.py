"""Fold-free results: one fold check for every method, convexity kept by the default solver,
an honest diagnosis where no fold-free PQ mesh is near, unmeetable fixed sets refused."""
import numpy as np
import pytest

from optimize import measures, optimize_mesh, shapes


def hypar(n=10, noise=0.0, seed=0):
    """z = x y meshed along its rulings (asymptotic lines: no conjugate net, no fold-free PQ mesh near)."""
    m = shapes.grid(n + 1, n + 1, size=(n, n), height=lambda x, y: 0.08 * (x - n / 2) * (y - n / 2))
    return shapes.perturbed(m, noise, seed=seed) if noise else m


@pytest.mark.parametrize("method", ["default", "penalty", "sqp", "hybrid"])
def test_fold_check_covers_every_method(method):
    mesh = hypar()
    res = optimize_mesh(mesh, "pq", method=method, max_iter=60)
    folded = measures.folded_faces(mesh, res.mesh.V)
    assert res.defects["folded"]["count"] == int(folded.sum())
    if folded.any():
        assert res.status != "converged" and not res.success, res.message
    assert res.success == (res.status == "converged")
