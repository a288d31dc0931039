"""The contract every method keeps (default, penalty, sqp, hybrid; every target each supports).

- invariance under rigid motion and uniform scale: the result moves with the input;
- fixed vertices stay bit-exactly where they were;
- an honest ``max_iter``: never more iterations than asked, and a run stopped by the
  budget says so (status ``max_iter``, the message names it);
- nothing non-finite in the result (positions, defects, history).
Small meshes and short budgets keep it fast; convergence itself is each method's own test.
"""
import math

import numpy as np
import pytest

from optimize.modelling import shapes
from optimize.api import optimize_mesh
from optimize.modelling.designs import trefoil_band_mesh
from optimize.options import DEFAULT_TARGETS, PAPER_METHODS

CASES = [("default", t) for t in DEFAULT_TARGETS] + [(m, t) for m in PAPER_METHODS
                                                      for t in DEFAULT_TARGETS + ("strip",)]
BUDGET = 12  # iterations per run: the contract holds at every iterate, not only at convergence
# Every case moves with its input (issue 31): the paper's methods solve in the input's canonical frame
# (optimize.solvers.paper.frame), and closest-point ties and the Moebius band's seam normals no longer
# depend on rounding (optimize.proximity.surface.TIE, _vertex_normals).  A case that does not is
# listed here with the reason (strict: a fix shows up as XPASS).
NOT_INVARIANT: dict[tuple[str, str], str] = {}


def _mesh(target):
    if target == "strip":
        return trefoil_band_mesh(24, 0.4)
    m0 = shapes.revolution(shapes.dome_profile(k=4), 8)
    return shapes.perturbed(m0, 0.03, seed=5)


def _rigid(V, scale):
    Q, _ = np.linalg.qr(np.random.default_rng(13).standard_normal((3, 3)))
    return scale * V @ Q.T + np.array([100.0, -50.0, 7.0])


def _run(mesh, method, target, **kw):
    kw.setdefault("max_iter", BUDGET)
    return optimize_mesh(mesh, target, method=method, **kw)


def _finite(res):
    assert np.all(np.isfinite(res.mesh.V)), res.message
    for key in ("planarity", "conical", "circular"):
        if key in res.defects:
            assert math.isfinite(res.defects[key]["max"]), (key, res.defects[key])
    for entry in res.history:
        for k, v in entry.items():
            if isinstance(v, float):
                assert not math.isnan(v), (k, entry)


@pytest.fixture(scope="module")
def base_runs():
    cache = {}

    def get(method, target):
        if (method, target) not in cache:
            cache[method, target] = _run(_mesh(target), method, target)
        return cache[method, target]

    return get


@pytest.mark.parametrize("method,target", [
    pytest.param(m, t, marks=pytest.mark.xfail(strict=True, reason=NOT_INVARIANT[m, t]))
    if (m, t) in NOT_INVARIANT else (m, t) for m, t in CASES])
def test_invariant_under_rigid_motion_and_scale(method, target, base_runs):
    mesh = _mesh(target)
    res = base_runs(method, target)
    _finite(res)
    for scale in (1000.0, 1e-3):
        moved = _run(mesh.with_vertices(_rigid(mesh.V, scale)), method, target)
        _finite(moved)
        assert moved.status == res.status and moved.nit == res.nit, (scale, moved.message, res.message)
        err = np.abs(moved.mesh.V - _rigid(res.mesh.V, scale)).max() / (scale * mesh.bbox_diagonal())
        assert err < 1e-6, (scale, err)


@pytest.mark.parametrize("method,target", CASES)
def test_fixed_vertices_stay_fixed(method, target):
    mesh = _mesh(target)
    fixed = np.array([0, 3, 7, mesh.n_vertices - 1])
    res = _run(mesh, method, target, fixed=fixed)
    _finite(res)
    np.testing.assert_array_equal(res.mesh.V[fixed], mesh.V[fixed])
    free = np.setdiff1d(np.arange(mesh.n_vertices), fixed)
    assert np.abs(res.mesh.V[free] - mesh.V[free]).max() > 0  # the others were free to move, and did


@pytest.mark.parametrize("method,target", CASES)
@pytest.mark.parametrize("budget", [0, 1, 3])
def test_max_iter_is_honest(method, target, budget):
    mesh = shapes.perturbed(_mesh(target), 0.05, seed=9)  # far enough that a few steps cannot finish
    res = _run(mesh, method, target, max_iter=budget)
    _finite(res)
    assert res.nit <= budget and len(res.history) <= budget, (res.nit, len(res.history), res.message)
    if not res.success:
        assert res.status in ("max_iter", "stalled", "folded", "diverged"), res.status
    if res.status == "max_iter":
        assert res.nit == budget and "max_iter" in res.message, res.message
    if budget == 0:
        assert res.status == "max_iter" and not res.success
        np.testing.assert_array_equal(res.mesh.V, mesh.V)  # no step taken, bit-exact input
