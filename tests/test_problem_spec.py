"""The one problem description (optimize.terms.problem) that the default and the paper's methods build from."""
import dataclasses

import numpy as np
import pytest

from optimize.errors import ConfigError, MeshError
from optimize.mesh import Mesh, measures
from optimize.modelling import shapes
from optimize.solvers.paper.problem import Problem
from optimize.terms import fixed as fixed_mod
from optimize.terms.formulation import Formulation
from optimize.terms.problem import TermSpec, describe


def revolution():
    """PQ, conical at every interior vertex and circular (isosceles trapezoids) by construction."""
    return shapes.revolution(shapes.dome_profile(k=5), 9)


def test_description_is_frozen():
    spec = describe(revolution(), "conical", "hybrid")
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.target = "pq"
    with pytest.raises(TypeError):
        spec.terms[0].options["faces"] = "ngons"
    with pytest.raises(ValueError, match="kind"):
        TermSpec("x", "planarity", "soft")


@pytest.mark.parametrize("method,kinds", [("penalty", {"least_squares"}), ("sqp", {"constraint"}),
                                          ("hybrid", {"least_squares", "constraint"}),
                                          ("default", {"least_squares"})])
def test_each_method_lists_the_kinds_its_solver_reads(method, kinds):
    spec = describe(revolution(), "conical", method, fairness=0.1, closeness=0.2)
    assert {t.kind for t in spec.terms} == kinds | {"energy"}
    energies = {t.name: t.weight for t in spec.rows("energy")}
    assert energies == {"fairness": 0.1, "closeness": 0.2}
    assert (spec.energies.fairness, spec.energies.closeness) == (0.1, 0.2)


def test_both_families_share_normalization_and_fixed_set():
    m = shapes.perturbed(shapes.grid(5, 4, size=(4.0, 3.0)), 0.1, seed=2)
    d = describe(m, "pq", "default", fixed=[6], glide_boundary=True)
    p = describe(m, "pq", "penalty", fixed=[6])
    centre, scale = measures.normalization(m)
    for spec in (d, p):
        assert np.array_equal(spec.centre, centre) and spec.scale == scale
        assert np.allclose(spec.normalized().V, (m.V - centre) / scale)
    assert np.array_equal(p.fixed, [6])
    assert np.array_equal(d.fixed, np.union1d([6], fixed_mod.corner_vertices(m)))  # gliding: corners stay
    assert list(p.layout.blocks) == ["vertices"]
    assert list(d.layout.blocks) == ["vertices", "normals"] and d.layout.blocks["normals"] == (m.n_faces, 3)
    problem = Problem(m, spec=p)
    assert np.array_equal(problem.free, np.setdiff1d(np.arange(3 * m.n_vertices), [18, 19, 20]))


@pytest.mark.parametrize("target", ["pq", "conical", "circular"])
@pytest.mark.parametrize("unknowns", ["auxiliary", "vertices"])
def test_default_rows_vanish_exactly_where_the_target_holds(target, unknowns):
    """Every row the description lists is evaluated, is zero on a mesh that meets the target by
    construction and not zero once the mesh is perturbed."""
    exact = revolution()
    spec = describe(exact, target, "default", formulation=unknowns)
    form = Formulation(exact, target, spec=spec)
    rows = spec.rows("least_squares")
    assert rows and [t.name for t in form.rows] == [t.name for t in rows]
    bent = shapes.perturbed(exact, 0.05, seed=3)
    bent_form = Formulation(bent, target, unknowns)
    for term in rows:
        r, _ = form._rows(term, form.start(exact.V))
        assert len(r) and np.abs(r).max() < 1e-9, term.name
        if term.module != "unit":  # the unit rows hold at the start on any mesh
            r, _ = bent_form._rows(term, bent_form.start(bent.V))
            assert np.abs(r).max() > 1e-4, term.name
    r, _, _ = form.split_terms(form.start(exact.V))
    assert len(r) == sum(len(form._rows(t, form.start(exact.V))[0]) for t in rows)


@pytest.mark.parametrize("target", ["pq", "conical", "circular"])
def test_paper_rows_vanish_exactly_where_the_target_holds(target):
    exact = revolution()
    bent = shapes.perturbed(exact, 0.05, seed=3)
    for sqp in (False, True):
        for mesh, zero in ((exact, True), (bent, False)):
            p = Problem(mesh, spec=describe(mesh, target, "hybrid"))
            c, _, blocks = p.constraints(p.x0(), sqp=sqp)
            kind = "constraint" if sqp else "least_squares"
            assert list(blocks) == [t.name for t in p.spec.rows(kind)]
            for name, rows in blocks.items():
                worst = np.abs(c[rows]).max()
                assert (worst < 1e-9) if zero else (worst > 1e-4), (sqp, name, worst)


def test_sqp_constraints_keep_ngon_angle_sums_and_the_determinants_mean():
    m = shapes.perturbed(shapes.capped_cylinder(), 0.02, seed=1)
    ngons = np.nonzero(m.face_sizes > 4)[0]
    assert len(ngons) and np.any(m.face_sizes == 4)
    spec = describe(m, "pq", "sqp")
    names = [(t.name, t.module, dict(t.options)) for t in spec.rows("constraint")]
    assert names == [("angle_sum", "facesum", {"faces": "ngons"}), ("det", "determinants", {"form": "mean"})]
    p = Problem(m, spec=spec)
    blocks = p.sqp_system.blocks
    assert blocks["angle_sum"].stop - blocks["angle_sum"].start == len(ngons)
    assert blocks["det"].stop - blocks["det"].start == np.count_nonzero(m.face_sizes == 4)
    assert p.terms == []  # no penalty rows in an SQP-only run


def test_default_mu_per_method():
    m = revolution()
    assert not any(t.module == "determinants" for t in describe(m, "pq", "penalty").terms)
    assert any(t.module == "determinants" for t in describe(m, "pq", "sqp").terms)
    assert "det" in describe(m, "pq", "hybrid").tests and "det" not in describe(m, "pq", "penalty").tests


def test_bad_descriptions_name_the_key():
    m = revolution()
    with pytest.raises(ConfigError, match="target"):
        describe(m, "strip", "default")
    with pytest.raises(ConfigError, match="method"):
        describe(m, "pq", "newton")
    with pytest.raises(ConfigError, match="formulation"):
        describe(m, "pq", "default", formulation="normals")
    with pytest.raises(ConfigError, match="weights"):
        describe(m, "pq", "penalty", fairness=-1.0)
    tri = Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]), [[0, 1, 2]])
    with pytest.raises(ConfigError, match="determinant"):
        describe(tri, "pq", "penalty", mu=1.0)
    with pytest.raises(MeshError, match="strip"):
        describe(shapes.grid(3, 3), "strip", "penalty")


def test_default_lists_gliding_and_convexity_after_the_target_rows():
    m = shapes.perturbed(shapes.grid(5, 4, size=(4.0, 3.0)), 0.1, seed=2)
    plain = describe(m, "pq", "default")
    spec = describe(m, "pq", "default", glide_boundary=True, convex=True)
    names = [t.name for t in spec.rows("least_squares")]
    assert names == [t.name for t in plain.rows("least_squares")] + ["glide", "edge_floor", "convexity"]
    t = m.topology
    corners = fixed_mod.corner_vertices(m)
    assert np.array_equal(spec.sets["glide"], np.setdiff1d(np.nonzero(t.is_boundary_vertex)[0], corners))
    E = spec.sets["glide_edges"]
    edge_id = {tuple(sorted(e)) for e in t.edges[t.is_boundary_edge].tolist()}
    assert len(E) and all(tuple(sorted(e)) in edge_id for e in E.tolist())  # boundary edges only
    assert np.isin(E, spec.sets["glide"]).any(axis=1).all()  # each at a gliding vertex
    assert [t.name for t in Formulation(m, "pq", spec=spec).rows] == [t.name for t in plain.rows("least_squares")]
