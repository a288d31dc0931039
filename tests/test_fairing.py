"""The constrained fairing phase (optimize.solvers.fairing, #31 item 1-2): after the guided solve,
fairness relative to the input and closeness are minimized with every constraint kept exact."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from optimize import optimize_mesh
from optimize.mesh import measures
from optimize.modelling import shapes
from optimize.solvers import fairing


def _vault():
    """A noisy translational surface (z = f(x) + g(y): PQ before the noise), 6 x 6 quads."""
    mesh = shapes.grid(7, 7, size=(6.0, 5.0), height=lambda x, y: 1.5 - 0.08 * (x - 3) ** 2 - 0.06 * (y - 2.5) ** 2)
    return shapes.perturbed(mesh, 0.08, seed=2)


def _run(mesh, target="pq", on=True):
    return optimize_mesh(mesh, target, refine=on)


@pytest.fixture(scope="module")
def pair():
    mesh = _vault()
    return mesh, _run(mesh, on=False), _run(mesh, on=True)


def test_phase_ran_and_constraints_exact(pair):
    mesh, plain, fair = pair
    assert fair.status == "converged", fair.message
    assert any(e.get("phase") == "fairing" for e in fair.history)
    assert fair.nit > plain.nit
    assert measures.planarity(fair.mesh).max() <= 1e-6


def test_fair_no_fold(pair):
    mesh, plain, fair = pair
    assert fair.defects["fairness"]["ratio"] <= 2.0
    assert fair.defects["folded"]["count"] == 0


def test_closer_on_a_real_roof():
    """The COMPAS tube shell (a Rhino mesh shipped in configs/meshes), PQ: the phase ends closer
    to the input surface than the guided solve alone (0.41% against 0.63% of the bbox diagonal),
    no rougher.  (On the small noisy vault above it is not: there it trades closeness for keeping
    the input's second differences; see the module docstring.)"""
    from optimize.mesh.io import read_mesh

    mesh = read_mesh(Path(__file__).resolve().parents[1] / "configs" / "meshes" / "compas_tubemesh.obj")
    plain, fair = _run(mesh, on=False), _run(mesh, on=True)
    assert fair.status == "converged" and fair.defects["folded"]["count"] == 0
    assert fair.defects["distance"]["max_relative"] < plain.defects["distance"]["max_relative"]
    assert fair.defects["fairness"]["ratio"] <= plain.defects["fairness"]["ratio"]


def test_rotation_invariant(pair):
    mesh, _, fair = pair
    a, b = 0.7, -0.4
    Rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    Rx = np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
    R = Rz @ Rx
    rot = _run(mesh.with_vertices(mesh.V @ R.T), on=True)
    assert rot.status == "converged"
    err = np.abs(rot.mesh.V - fair.mesh.V @ R.T).max() / mesh.bbox_diagonal()
    assert err <= 1e-6


def test_balance_is_the_one_knob():
    assert fairing.balance(1e-3, 1e-2) == pytest.approx((1 / 11, 10 / 11))
    assert fairing.balance(0.0, 0.0) == (0.0, 0.0)
