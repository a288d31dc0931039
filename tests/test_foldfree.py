"""Fold-free results: one fold check for every method, convexity kept by the default solver,
an honest diagnosis where no fold-free PQ mesh is near, unmeetable fixed sets refused."""
import numpy as np
import pytest

from optimize import optimize_mesh
from optimize.mesh import measures
from optimize.modelling import shapes


def hypar(n=10, noise=0.0, seed=0):
    """z = x y meshed along its rulings (asymptotic lines: no conjugate net, no fold-free PQ mesh near)."""
    m = shapes.grid(n + 1, n + 1, size=(n, n), height=lambda x, y: 0.08 * (x - n / 2) * (y - n / 2))
    return shapes.perturbed(m, noise, seed=seed) if noise else m


@pytest.mark.parametrize("method", ["default", "penalty", "sqp", "hybrid"])
def test_fold_check_covers_every_method(method):
    mesh = hypar(8)
    res = optimize_mesh(mesh, "pq", method=method, max_iter=40)
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
    assert "found no fold-free PQ mesh near" in res.message and "--remesh auto" in res.message
    assert str(held["faces"][0]) in res.message


@pytest.mark.parametrize("target,formulation", [("pq", "auxiliary"), ("pq", "vertices"),
                                                ("conical", "vertices"), ("conical", "auxiliary"),
                                                ("circular", "auxiliary"), ("circular", "vertices")])
def test_convexity_holds_after_every_accepted_iteration(target, formulation):
    mesh = hypar(7, noise=0.02, seed=1)
    seen = []
    res = optimize_mesh(mesh, target, formulation=formulation, max_iter=12, callback=seen.append)
    assert seen and [h["folded"] for h in seen] == [0] * len(seen)
    assert not measures.folded_faces(mesh, res.mesh.V).any()
    if target == "pq":  # (the conical / circular runs happen not to fold here even without the rows)
        old = optimize_mesh(mesh, target, formulation=formulation, max_iter=12, convex=False)
        assert max(h["folded"] for h in old.history) > 0  # without the rows, iterates do fold here


def test_convexity_rows_gradient_matches_finite_differences():
    from optimize import Mesh
    from optimize.terms import convexity
    from optimize.terms.variables import Layout

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
    from fabricate.app.cli import main
    from optimize.mesh.io import write_mesh

    src = tmp_path / "in.obj"
    write_mesh(src, conjugate_grid())
    assert main(["optimize", str(src), "-o", str(tmp_path / "out.obj")]) == 0
    out = capsys.readouterr().out
    assert "mm diagonal (" in out and "%), mean" in out and "fairness (mean second difference" in out
    assert "folded faces: 0" in out
    strip = shapes.perturbed(shapes.grid(6, 2, size=(5, 1), height=lambda x, y: 0.1 * x * y), 0.1, seed=3)
    write_mesh(src, strip)
    assert main(["optimize", str(src), "-o", str(tmp_path / "out2.obj"), "--fix", "boundary"]) == 2
    assert not (tmp_path / "out2.obj").exists()


def test_near_pq_input_keeps_its_fairness_and_barely_moves(monkeypatch):
    from optimize.solvers import guided

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
    from optimize.mesh.conjugacy import net_defect

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


def test_remesh_route_finds_a_fold_free_pq_mesh_where_the_input_lines_cannot():
    from optimize.remesh.routes import optimize_routes

    mesh = hypar(9)
    chosen, routes = optimize_routes(mesh, "pq", remesh="auto")
    original, remeshed = routes  # asymptotic lines: the remeshed route is tried
    assert original.name == "original" and remeshed.name == "remeshed" and chosen is remeshed
    o = original.result
    assert not o.success or o.defects["distance"]["max_relative"] > remeshed.result.defects["distance"]["max_relative"]
    res = remeshed.result
    assert res.success and res.defects["folded"]["count"] == 0
    assert res.defects["distance"]["max_relative"] < 0.005  # within 0.5% of the input surface
    assert [r["route"] for r in (original.as_dict(), remeshed.as_dict())] == ["original", "remeshed"]
    chosen, routes = optimize_routes(conjugate_grid(), "pq", remesh="auto")  # the own lines work: kept
    assert len(routes) == 1 and chosen.name == "original" and chosen.result.success
    chosen, routes = optimize_routes(conjugate_grid(), "pq", remesh="never")
    assert len(routes) == 1


def test_config_input_remesh_is_for_mesh_inputs(tmp_path):
    from fabricate.app.config import load_config
    from optimize.errors import ConfigError
    from optimize.mesh.io import write_mesh

    write_mesh(tmp_path / "h.obj", hypar())
    (tmp_path / "a.yaml").write_text("input: {mesh: h.obj, remesh: auto}\n")
    assert load_config(tmp_path / "a.yaml").input.remesh == "auto"
    (tmp_path / "b.yaml").write_text("input: {shape: {name: dome}, remesh: auto}\n")
    with pytest.raises(ConfigError, match="remesh applies only to a mesh input"):
        load_config(tmp_path / "b.yaml")
    (tmp_path / "c.yaml").write_text("input: {mesh: h.obj, remesh: sometimes}\n")
    with pytest.raises(ConfigError, match="input.remesh"):
        load_config(tmp_path / "c.yaml")


def test_fabricate_run_with_input_remesh_reports_both_routes(tmp_path):
    import json

    from fabricate.app.config import load_config
    from fabricate.app.pipeline import run_pipeline
    from optimize.mesh.io import write_mesh

    mesh = hypar(8)
    write_mesh(tmp_path / "h.obj", mesh.with_vertices(mesh.V * 1000.0))  # metres of design, in mm
    (tmp_path / "r.yaml").write_text("input: {mesh: h.obj, remesh: auto}\noptimize: {target: pq}\n"
                                     "outputs: {step: false, stl: false, 3mf: false, dxf: false, svg: false, "
                                     "bom: false, pictures: false, html: false}\n")
    summary = run_pipeline(load_config(tmp_path / "r.yaml"), tmp_path / "out")
    report = json.loads((tmp_path / "out" / "r" / "report.json").read_text())
    routes = report["input"]["routes"]
    assert [r["route"] for r in routes] == ["own lines", "remeshed along principal directions"]
    assert [r["chosen"] for r in routes] == [False, True]
    assert routes[1]["success"] and routes[1]["folded"] == 0  # the original: exact but 4% away, or held
    assert routes[1]["distance"]["max_relative"] < min(0.005, routes[0]["distance"]["max_relative"])
    assert summary.faces == routes[1]["faces"], summary


def test_fold_check_of_the_solver_agrees_with_measures_folded_faces():
    from optimize.terms.convexity import FoldCheck

    mesh = hypar(6, noise=0.05)
    check = FoldCheck(mesh, mesh.V)
    rng = np.random.default_rng(0)
    for amount in (0.0, 0.2, 0.6, 1.2):
        V = mesh.V + amount * rng.standard_normal(mesh.V.shape)
        assert np.array_equal(check.faces(V), measures.folded_faces(mesh, V))
    assert check.faces(mesh.V[:, [1, 0, 2]]).all()  # mirrored: every normal flipped


def test_fold_advice_fits_the_target():
    """A folded run of the paper's methods advises the default method where it exists (pq,
    conical, circular) and, for a strip (which runs the paper's methods only), another of those."""
    from optimize.errors import ConfigError
    from optimize.mesh import Mesh
    from optimize.modelling.designs import trefoil_band_mesh

    grid = shapes.perturbed(shapes.grid(5, 4, (4.0, 3.0)), 0.1, seed=4)
    res = optimize_mesh(grid, "pq", method="sqp")
    assert res.status == "folded", res.message
    assert res.message.endswith("the default method does (method 'default', --method default)")
    band = trefoil_band_mesh(30, 0.4)
    band = Mesh(band.V + 0.02 * np.random.default_rng(1).standard_normal(band.V.shape), band.F, name="band")
    res = optimize_mesh(band, "strip", method="sqp")
    assert res.status == "folded", res.message
    assert "--method default" not in res.message and "method 'default'" not in res.message
    assert "target 'strip' has no other method" in res.message and "--method penalty" in res.message
    with pytest.raises(ConfigError, match="strip"):
        optimize_mesh(band, "strip", method="default")  # the method the pq advice names is no option here


def test_the_fold_threshold_is_the_runs_tolerance():
    """``Tolerances.fold`` reaches the fold check: the face that folds on this grid turns its
    corner to a sine below -0.3, so a threshold of 0.9 lets it pass and the run converges."""
    from optimize import Tolerances

    grid = shapes.perturbed(shapes.grid(5, 4, (4.0, 3.0)), 0.1, seed=4)
    strict = optimize_mesh(grid, "pq", method="sqp")
    assert strict.status == "folded" and strict.defects["folded"]["count"] > 0
    loose = optimize_mesh(grid, "pq", method="sqp", tol=Tolerances(fold=0.9))
    assert loose.status == "converged" and loose.defects["folded"]["count"] == 0, loose.message
    assert not measures.folded_faces(grid, loose.mesh.V, tol=0.9).any()
    assert measures.folded_faces(grid, loose.mesh.V).any()  # the default threshold still sees the fold
