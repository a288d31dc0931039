"""Rationalization (#37 item 3): near-congruent panels pulled into exact classes, the mesh kept conical.
The congruence rows' Jacobian is checked by finite differences; on a noisy dome of 12 x 3 quads (36
shapes) the pull brings the panels into the 3 shapes its construction has (one per ring)."""
import numpy as np
import pytest

from optimize.api import optimize_mesh
from optimize.errors import ConfigError
from optimize.mesh.congruence import face_classes
from optimize.modelling import shapes
from optimize.options import OptimizeOptions
from optimize.terms import congruence
from optimize.terms.variables import Layout


def _noisy_dome():
    m = shapes.revolution(shapes.dome_profile(6000.0, 2500.0, 4), 12, name="dome")
    return shapes.perturbed(m, 0.02, seed=1)


def test_congruence_rows_finite_differences():
    rng = np.random.default_rng(0)
    V = rng.standard_normal((6, 3))
    L = Layout.vertices_only(6)
    corners = np.array([[0, 1, 2, 3], [5, 4, 1, 0]])
    target = rng.uniform(1, 2, (2, 6))
    x = V.ravel()
    r, J = congruence.terms(x, L, corners, target)
    assert r.shape == (12,) and np.allclose(r + target.ravel(), congruence.distances(V, corners).ravel())
    eps = 1e-7
    fd = np.stack([(congruence.terms(x + eps * e, L, corners, target)[0] - r) / eps for e in np.eye(x.size)], 1)
    assert np.abs(J.toarray() - fd).max() < 1e-5


def test_rationalize_dome_to_its_three_rings():
    dome = _noisy_dome()
    plain = optimize_mesh(dome, "conical")
    assert face_classes(plain.mesh).count == 36                       # noise: every panel its own shape
    res = optimize_mesh(dome, "conical", rationalize=100.0)
    assert res.success
    rec = res.defects["rationalize"]
    assert rec["before"]["shapes"] == 36 and rec["after"]["shapes"] == 3
    assert face_classes(res.mesh).count == 3
    assert res.defects["conical"]["max"] <= 1e-6 and res.defects["planarity"]["max"] <= 1e-6
    limit = 5e-3 * np.linalg.norm(np.ptp(dome.V, axis=0))            # tolerances.closeness of the diagonal
    assert res.defects["distance"]["max"] <= max(limit, plain.defects["distance"]["max"])
    assert rec["after"]["max_distance"] == pytest.approx(res.defects["distance"]["max"], rel=1e-6)


def test_rationalize_off_by_default_and_checked():
    assert OptimizeOptions().rationalize is None
    for bad in (0, -1.0, float("nan"), True, 1e9):
        with pytest.raises(ConfigError, match="rationalize"):
            OptimizeOptions(rationalize=bad)
    with pytest.raises(ConfigError, match="rationalize"):
        OptimizeOptions(method="penalty", rationalize=5.0)
