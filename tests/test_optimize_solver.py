"""The default optimizer end to end: every target reaches tolerance, invariance under rigid
motion and scale, fixed and gliding vertices, honest non-convergence, pure (inputs untouched)."""
import numpy as np
import pytest

from optimize import ConfigError, Tolerances, optimize_mesh
from optimize.mesh import measures
from optimize.modelling import shapes
from optimize.proximity import Reference
from optimize.mesh.io import read_mesh

from conftest import TUNNEL


@pytest.fixture(scope="module")
def noisy_dome():
    base = shapes.revolution(shapes.dome_profile(k=8), 16)
    return shapes.perturbed(base, 0.04, seed=11)


@pytest.mark.parametrize("formulation", ["auxiliary", "vertices"])
@pytest.mark.parametrize("target,key", [("pq", None), ("conical", "conical"), ("circular", "circular")])
def test_each_target_reaches_tolerance_on_perturbed_revolution(noisy_dome, target, key, formulation):
    V0 = noisy_dome.V.copy()
    res = optimize_mesh(noisy_dome, target, formulation=formulation)
    assert res.success and res.status == "converged", res.message
    np.testing.assert_array_equal(noisy_dome.V, V0)  # pure: the input is untouched
    np.testing.assert_array_equal(res.mesh.F, noisy_dome.F)
    tol = Tolerances()
    assert measures.planarity(res.mesh).max() <= tol.planarity
    if key == "conical":
        assert measures.conical_defect(res.mesh).max() <= tol.conical
        t = res.mesh.topology
        n = measures.face_normals(res.mesh)[t.star_faces[t.interior_valence4, :4]]
        cosines = np.einsum("psj,pj->ps", n, res.axes[t.interior_valence4])
        # node axes make one angle with the four face normals
        assert np.ptp(cosines, axis=1).max() < 1e-6
        np.testing.assert_allclose(np.cos(res.cone_angles[t.interior_valence4]), cosines[:, 0], atol=1e-6)
        np.testing.assert_allclose(np.linalg.norm(res.axes, axis=1), 1.0)
    if key == "circular":
        assert measures.circular_defect(res.mesh).max() <= tol.circular
    assert res.defects["planarity"]["ok"]
    assert res.max_distance < 0.02
    assert all(np.isfinite(h["planarity"]) for h in res.history)
    assert res.history[-1]["planarity"] <= tol.planarity


@pytest.mark.parametrize("target,formulation", [("pq", "auto"), ("conical", "auto"), ("circular", "auto"),
                                                ("conical", "auxiliary")])
def test_data_tunnel(target, formulation):
    """The shipped forking tunnel (784 quads, three loops, valence-3 and -5 vertices, in metres)."""
    mesh = read_mesh(TUNNEL)
    res = optimize_mesh(mesh, target, formulation=formulation)
    assert res.success, res.message
    assert res.max_distance < 0.005  # goal: under 0.5% of the bounding-box diagonal
    ref = Reference(mesh)
    assert ref.distance(res.mesh.V).max() / mesh.bbox_diagonal() == pytest.approx(res.max_distance, rel=1e-9)


def test_tunnel_conical_beams_are_torsion_free_at_its_irregular_nodes(small_tunnel):
    from fabricate.offset import offset_structure

    mesh = small_tunnel  # 196 quads, metres; the same irregular nodes as the shipped 784
    t = mesh.topology
    inner = ~t.is_boundary_vertex
    # where the angle balance says nothing
    assert np.sum(inner & (t.star_size == 5)) == 6 and np.sum(inner & (t.star_size == 3)) == 2
    assert len(t.boundary_loops) == 3
    res = optimize_mesh(mesh, "conical")  # torsion_free_beams="auto": on, the mesh is irregular
    assert res.success, res.message
    assert res.beam_axes is not None and np.all(np.isfinite(res.beam_axes))
    assert res.history[-1]["beam"] <= 1e-6 and res.history[-1]["node_cone"] <= 1e-6
    s = offset_structure(res.mesh, [0.0, -0.2], axes=res.beam_axes)  # metres: a 200 mm beam
    assert np.abs(s.beam_twist_mm).max() < 1e-7  # model units: 0.1 micrometre
    assert np.abs(s.face_distance_error).max() < 1e-6
    # without the node axes the same mesh's beams at the irregular nodes twist by centimetres
    plain = optimize_mesh(mesh, "conical", torsion_free_beams=False)
    assert plain.success and plain.beam_axes is None
    assert np.abs(offset_structure(plain.mesh, [0.0, -0.2]).beam_twist_mm).max() > 0.01


def test_data_cylinder_with_ngons_is_already_done():
    mesh = shapes.capped_cylinder()
    res = optimize_mesh(mesh, "conical")
    assert res.success and res.nit == 0
    np.testing.assert_array_equal(res.mesh.V, mesh.V)


@pytest.mark.parametrize("target,formulation", [("pq", "auxiliary"), ("pq", "vertices"), ("conical", "auto")])
def test_ngon_caps_become_planar(target, formulation):
    mesh = shapes.perturbed(shapes.capped_cylinder(), 0.05, seed=12)
    assert measures.planarity(mesh).max() > 1e-2
    res = optimize_mesh(mesh, target, formulation=formulation)
    assert res.success, res.message
    assert measures.planarity(res.mesh)[mesh.face_sizes > 4].max() <= 1e-6
    if target == "conical":
        assert measures.conical_defect(res.mesh).max() <= 1e-6


def test_zero_motion_on_exact_meshes():
    u = np.linspace(0, 2, 7)
    mesh = shapes.translational(np.stack([u, 0 * u, np.sin(u)], 1), np.stack([0 * u, u, u ** 2 / 3], 1))
    res = optimize_mesh(mesh, "pq")
    assert res.success and res.nit == 0 and res.max_distance == 0.0


def _rigid(V, scale):
    rng = np.random.default_rng(13)
    Q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    return scale * V @ Q.T + np.array([100.0, -50.0, 7.0]), Q


@pytest.mark.parametrize("target", ["pq", "conical"])
def test_invariance_under_rigid_motion_and_scale(noisy_dome, target):
    res = optimize_mesh(noisy_dome, target)
    for scale in (1.0, 1000.0, 1e-3):
        W, Q = _rigid(noisy_dome.V, scale)
        moved = optimize_mesh(noisy_dome.with_vertices(W), target)
        assert moved.success and moved.nit == res.nit
        back, _ = _rigid(res.mesh.V, scale)
        err = np.abs(moved.mesh.V - back).max() / (scale * noisy_dome.bbox_diagonal())
        assert err < 1e-7, (scale, err)
        # max_distance is relative to the axis-aligned bbox diagonal, which rotation changes
        absolute = moved.max_distance * noisy_dome.with_vertices(W).bbox_diagonal() / scale
        assert absolute == pytest.approx(res.max_distance * noisy_dome.bbox_diagonal(), rel=1e-5)


def test_fixed_vertices_do_not_move():
    # z = f(x) + g(y): the grid is a conjugate net, so a fold-free PQ mesh exists
    mesh = shapes.perturbed(shapes.grid(8, 7, height=lambda x, y: 0.3 * x ** 2 + 0.2 * y ** 2), 0.05, seed=14)
    for fixed in ("boundary", "corners", [5, 17, 30]):
        res = optimize_mesh(mesh, "pq", fixed=fixed)
        assert res.success, (fixed, res.message)
        idx = {"boundary": np.nonzero(mesh.topology.is_boundary_vertex)[0],
               "corners": np.array([0, 6, 49, 55])}.get(fixed, np.array(fixed)) if isinstance(fixed, str) else np.array(fixed)
        np.testing.assert_array_equal(res.mesh.V[idx], mesh.V[idx])
        assert np.abs(res.mesh.V - mesh.V).max() > 1e-6  # others did move


def test_folded_faces_are_not_a_success():
    # z = x y meshed along its rulings (asymptotic lines, no conjugate net): with the noisy
    # boundary fixed, planarity is reached only by denting quads (reflex corners of 30-65 deg)
    mesh = shapes.perturbed(shapes.grid(8, 7, height=lambda x, y: 0.5 * x * y), 0.05, seed=14)
    res = optimize_mesh(mesh, "pq", fixed="boundary", convex=False)  # without the convexity rows
    assert res.defects["planarity"]["ok"]  # every tolerance is met ...
    assert res.status == "folded" and not res.success  # ... but the panels are not cuttable
    assert res.defects["folded"]["count"] > 0 and "dented, flipped" in res.message
    folded = measures.folded_faces(mesh, res.mesh.V)
    assert folded.sum() == res.defects["folded"]["count"]


def test_folded_faces_measure_on_hand_made_quads():
    from optimize import Mesh

    square = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2, 3]])
    dented = square.V.copy()
    dented[2] = [0.3, 0.3, 0.0]  # corner 2 pushed inside: a reflex corner at vertex 2
    flipped = square.V[:, [1, 0, 2]]  # mirrored: the normal turns by 180 degrees
    assert not measures.folded_faces(square, square.V).any()
    assert measures.folded_faces(square, dented).all()
    assert measures.folded_faces(square, flipped).all()
    collapsed = square.V.copy()
    collapsed[1] = [1e-5, 0.0, 0.0]  # vertex 1 slid onto vertex 0: a triangle with a zero edge
    assert measures.folded_faces(square, collapsed).all()
    short = square.V.copy()
    short[1] = [0.1, 0.0, 0.0]  # a short edge, still a quad
    assert not measures.folded_faces(square, short).any()
    assert measures.corner_turns(square).min() == pytest.approx(1.0)


def test_boundary_glides_on_reference_boundary():
    ref = shapes.grid(9, 8, height=lambda x, y: 0.4 * np.sin(2 * x) + 0.3 * y ** 2)
    mesh = shapes.perturbed(ref, 0.03, seed=15)
    res = optimize_mesh(mesh, "pq", reference=ref, glide_boundary=True)
    assert res.success, res.message
    from optimize.proximity import BoundaryCurve

    corners = np.array([0, 7, 64, 71])  # fixed when gliding: they cannot slide round a kink
    np.testing.assert_array_equal(res.mesh.V[corners], mesh.V[corners])
    bnd = np.setdiff1d(np.nonzero(mesh.topology.is_boundary_vertex)[0], corners)
    Y, _ = BoundaryCurve(ref).closest(res.mesh.V[bnd])
    assert np.linalg.norm(Y - res.mesh.V[bnd], axis=1).max() < 1e-6 * ref.bbox_diagonal()


def test_budget_too_small_is_reported_honestly(noisy_dome):
    res = optimize_mesh(shapes.perturbed(noisy_dome, 0.3, seed=16), "conical", max_iter=2)
    assert not res.success and res.status == "max_iter" and res.nit == 2
    assert "max_iter" in res.message
    assert not res.defects["conical"]["ok"]
    assert np.all(np.isfinite(res.mesh.V))
    assert res.report()["success"] is False


def test_impossible_constraints_stall():
    # fixing every vertex of a non-planar mesh: nothing can move, nothing can converge
    mesh = shapes.perturbed(shapes.grid(3, 3), 0.1, seed=17)  # the centre must lie on 4 fixed planes
    res = optimize_mesh(mesh, "pq", fixed="boundary", max_iter=50)
    assert not res.success and res.status == "stalled", res.message
    assert res.defects["planarity"]["ok"] is False
    bnd = np.nonzero(mesh.topology.is_boundary_vertex)[0]
    np.testing.assert_array_equal(res.mesh.V[bnd], mesh.V[bnd])


@pytest.mark.parametrize("kwargs,match", [({"target": "flat"}, "target"), ({"method": "newton"}, "method"),
                                          ({"fairness": -1.0}, "fairness"), ({"fixed": "edges"}, "fixed"),
                                          ({"linear_solver": "magic"}, "linear_solver"),
                                          ({"formulation": "normals"}, "formulation"),
                                          ({"method": "penalty", "formulation": "vertices"},
                                           "settings of the default method")])
def test_bad_settings_raise_config_error(kwargs, match):
    with pytest.raises(ConfigError, match=match):
        optimize_mesh(shapes.grid(3, 3), **kwargs)


@pytest.mark.parametrize("backend", ["superlu", "eliminate", "pardiso"])
def test_linear_solver_backends_agree(noisy_dome, backend):
    a = optimize_mesh(noisy_dome, "circular")
    b = optimize_mesh(noisy_dome, "circular", linear_solver=backend)
    assert b.success
    assert np.abs(a.mesh.V - b.mesh.V).max() < 1e-3 * noisy_dome.bbox_diagonal()


def test_history_records_every_defect_and_energy(noisy_dome):
    seen = []
    res = optimize_mesh(noisy_dome, "conical", callback=seen.append)
    assert len(seen) == res.nit == len(res.history)
    for key in ("planarity", "conical", "fairness", "closeness", "step", "objective", "mu"):
        assert key in res.history[0]
    assert res.timings["total"] > 0 and res.timings["solve"] > 0


def test_paper_method_options_reach_the_paper_solver(monkeypatch):
    # (that a default run does not import the paper's stack: tests/test_startup.py, in a subprocess)
    import optimize.solvers.paper

    seen = {}

    def fake(mesh, target, **kwargs):
        seen.update(kwargs, target=target)
        return "from paper"

    monkeypatch.setattr(optimize.solvers.paper, "run_paper_method", fake)
    mesh = shapes.grid(3, 3)
    assert optimize_mesh(mesh, "strip", method="sqp", kkt_tol=1e-9) == "from paper"
    assert seen["method"] == "sqp" and seen["target"] == "strip" and seen["kkt_tol"] == 1e-9
    with pytest.raises(ConfigError, match="only for the paper"):
        optimize_mesh(mesh, "pq", kkt_tol=1e-9)
    with pytest.raises(ConfigError, match="paper's methods only"):
        optimize_mesh(mesh, "strip")


def test_divergence_is_detected_and_the_last_good_iterate_kept(noisy_dome, monkeypatch):
    from optimize import linalg

    calls = {"n": 0}
    real = linalg.NormalSolver.solve

    def flaky(self, A, b):
        calls["n"] += 1
        x = real(self, A, b)
        return x if calls["n"] <= 2 else np.full_like(x, np.nan)  # a solver gone bad

    monkeypatch.setattr(linalg.NormalSolver, "solve", flaky)
    res = optimize_mesh(noisy_dome, "conical")
    assert res.status == "diverged" and not res.success
    assert "non-finite" in res.message and res.nit >= 1
    assert np.all(np.isfinite(res.mesh.V))
