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


def conjugate_grid(n=8, noise=0.1, seed=2):
    """A translational surface z = f(x) + g(y) (its grid lines are a conjugate net: PQ as it
    is) with seeded noise of ``noise`` edge lengths: a fold-free PQ mesh lies close by."""
    m = shapes.grid(n + 1, n + 1, size=(n, n), height=lambda x, y: 0.5 * np.sin(0.6 * x) + 0.04 * (y - n / 2) ** 2)
    return shapes.perturbed(m, noise, seed=seed)


@pytest.mark.parametrize("target,formulation", [("pq", "auxiliary"), ("pq", "vertices"),
                                                ("conical", "vertices"), ("circular", "auxiliary")])
def test_perturbed_conjugate_grid_becomes_exact_and_fold_free(target, formulation):
    mesh = conjugate_grid()
    res = optimize_mesh(mesh, target, formulation=formulation)
    assert res.status == "converged" and res.success, res.message
    assert not measures.folded_faces(mesh, res.mesh.V).any()
    assert measures.planarity(res.mesh).max() <= 1e-6


def test_no_fold_free_pq_mesh_nearby_is_a_diagnosis_not_converged():
    mesh = hypar(noise=0.02, seed=1)
    old = optimize_mesh(mesh, "pq", convex=False)  # the earlier behaviour: planar by denting quads
    assert old.status == "folded" and old.defects["folded"]["count"] > 0
    res = optimize_mesh(mesh, "pq")
    assert res.status in ("stalled", "max_iter") and not res.success
    assert res.defects["folded"]["count"] == 0 and not measures.folded_faces(mesh, res.mesh.V).any()
    held = res.defects["convexity"]
    assert held["held"] > 0 and held["faces"]
    assert "no fold-free PQ mesh is near" in res.message and str(held["faces"][0]) in res.message


@pytest.mark.parametrize("target,formulation", [("pq", "auxiliary"), ("pq", "vertices"),
                                                ("conical", "vertices"), ("conical", "auxiliary"),
                                                ("circular", "auxiliary"), ("circular", "vertices")])
def test_convexity_holds_after_every_accepted_iteration(target, formulation):
    mesh = hypar(noise=0.02, seed=1)
    seen = []
    res = optimize_mesh(mesh, target, formulation=formulation, max_iter=25, callback=seen.append)
    assert seen and [h["folded"] for h in seen] == [0] * len(seen)
    assert not measures.folded_faces(mesh, res.mesh.V).any()
    if (target, formulation) != ("conical", "vertices"):  # that one happens not to fold here anyway
        old = optimize_mesh(mesh, target, formulation=formulation, max_iter=25, convex=False)
        assert max(h["folded"] for h in old.history) > 0  # without the rows, iterates do fold here


def test_convexity_rows_gradient_matches_finite_differences():
    from optimize import Mesh
    from optimize.constraints import convexity
    from optimize.variables import Layout

    pent = Mesh([[0, 0, 0], [1, 0, 0.1], [1.5, 1, 0], [0.5, 1.6, 0.2], [-0.3, 1, 0]], [[0, 1, 2, 3, 4]])
    for mesh in (pent, hypar(3, noise=0.2)):
        L = Layout().add("vertices", mesh.n_vertices, 3)
        x = mesh.V.ravel().copy()
        corners = np.arange(len(mesh.topology.corner_face))
        floor = np.full(len(corners), 2.0)  # every row acting (a sine is never above 1)
        r, J = convexity.terms(x, L, mesh, corners, floor)
        assert np.allclose(r, measures.corner_turns(mesh) - 2.0)
        eps, Jn = 1e-6, np.zeros(J.shape)
        for i in range(len(x)):
            d = np.zeros_like(x)
            d[i] = eps
            Jn[:, i] = (convexity.terms(x + d, L, mesh, corners, floor)[0]
                        - convexity.terms(x - d, L, mesh, corners, floor)[0]) / (2 * eps)
        assert np.abs(J.toarray() - Jn).max() < 1e-7
        r, J = convexity.terms(x, L, mesh, corners, np.full(len(corners), -2.0))  # none acting
        assert not r.any() and J.nnz == 0


def test_unmeetable_fixed_set_is_refused_before_iterating():
    from optimize.errors import ConfigError

    strip = shapes.perturbed(shapes.grid(6, 2, size=(5, 1), height=lambda x, y: 0.1 * x * y), 0.1, seed=3)
    seen = []
    with pytest.raises(ConfigError) as err:
        optimize_mesh(strip, "pq", fixed="boundary", callback=seen.append)
    assert not seen  # said before the first iteration
    bad = np.nonzero(measures.planarity(strip) > 1e-6)[0]
    assert "faces " + str(bad[:10].tolist()) in str(err.value) and "'boundary'" in str(err.value)
    res = optimize_mesh(strip, "pq", fixed="corners")  # meetable: runs
    assert res.nit > 0


def test_cli_optimize_prints_distance_fairness_and_folds(tmp_path, capsys):
    from fabricate.cli import main
    from optimize.io import write_mesh

    src = tmp_path / "in.obj"
    write_mesh(src, conjugate_grid())
    assert main(["optimize", str(src), "-o", str(tmp_path / "out.obj")]) == 0
    out = capsys.readouterr().out
    assert "% of the bbox diagonal), mean" in out and "fairness (mean second difference" in out
    assert "folded faces: 0" in out
    strip = shapes.perturbed(shapes.grid(6, 2, size=(5, 1), height=lambda x, y: 0.1 * x * y), 0.1, seed=3)
    write_mesh(src, strip)
    assert main(["optimize", str(src), "-o", str(tmp_path / "out2.obj"), "--fix", "boundary"]) == 2
    assert not (tmp_path / "out2.obj").exists()


def test_near_pq_input_keeps_its_fairness_and_barely_moves(monkeypatch):
    from optimize import guided

    base = shapes.revolution(shapes.dome_profile(k=9), 12)  # PQ by construction
    mesh = shapes.perturbed(base, 2e-4, seed=4)  # planar to about 1e-3: nearly there
    h = measures.edge_lengths(mesh).mean()
    res = optimize_mesh(mesh, "pq")
    assert res.success, res.message
    fair, dist = res.defects["fairness"], res.defects["distance"]
    assert 0.5 <= fair["ratio"] <= 2.0
    assert dist["max"] < 3e-3 * h  # about its noise (2e-4 h per coordinate), not a fairing step
    monkeypatch.setattr(guided, "FAR", None)  # the fairness weight in full, as before
    old = optimize_mesh(mesh, "pq")
    assert old.defects["distance"]["max"] > 3 * dist["max"]


def test_net_defect_tells_conjugate_asymptotic_and_principal_nets_apart():
    from optimize.conjugacy import net_defect

    translational = shapes.grid(9, 9, size=(8, 8), height=lambda x, y: 0.5 * np.sin(0.6 * x) + 0.04 * y ** 2)
    d = net_defect(translational)  # z = f(x) + g(y): its grid lines are a conjugate net
    assert d.mean_conjugacy < 1e-9 and not d.far("pq")
    d = net_defect(hypar())  # the rulings of z = x y: an asymptotic net
    assert d.mean_conjugacy > 0.99 and d.far("pq") and "far" in d.line("pq")
    dome = shapes.revolution(shapes.dome_profile(k=9), 16)  # meridians and parallels: principal
    d = net_defect(dome)
    assert d.mean_conjugacy < 1e-6 and d.mean_principal_angle < 1e-3 and not d.far("conical")
    sheared = dome.with_vertices(dome.V @ np.array([[1, 0.0, 0], [0.6, 1, 0], [0, 0, 1]]))  # lines off principal
    assert net_defect(sheared).mean_principal_angle > 5
