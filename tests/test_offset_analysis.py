"""Offset stage on meshes that are PQ but not conical, the paper's Remark, focal meshes.

The twist and face-distance figures are checked against plain loop
references written here from the definitions.
"""
from __future__ import annotations

import numpy as np
import pytest

from fabricate.offset.axes import AXIS_NEAR, AXIS_RCOND, NEAR_CONICAL
from fabricate.offset import (axis_line_intersections, edge_families, focal_meshes, offset_structure,
                              quad_circular_defect, require_pq)
from optimize import Tolerances
from optimize.modelling import shapes
from optimize.api import optimize_mesh
from optimize.errors import MeshError
from optimize.mesh.measures import conical_defect, planarity, quad_planarity

DIST = (0.0, 20.0, 120.0)


def translational(b_flat_until=None):
    """PQ, not conical; with ``b_flat_until`` the y-profile is straight and level up to that
    parameter, so the vertices there are conical (a cylinder) and the others are not."""
    u = np.linspace(0.0, 1.0, 9)
    a = np.stack([6000 * u, 0 * u, 1500 * np.sin(2 * u)], axis=1)
    g = 900 * np.cos(2.5 * u)
    if b_flat_until is not None:
        g = np.where(u <= b_flat_until, 0.0, 2000 * (u - b_flat_until) ** 2)
    b = np.stack([0 * u, 5000 * u, g], axis=1)
    return shapes.translational(a, b, name="translational")


def _newell(P):
    n = np.zeros(3)
    for i in range(len(P)):
        n += np.cross(P[i], P[(i + 1) % len(P)])
    return n / np.linalg.norm(n)


def reference_offsets(mesh):
    """Loop reference: per vertex, the minimum-norm least-squares X with n_i . X = 1; at a conical
    vertex (its face angles to the axis agree within NEAR_CONICAL) with the cut-off AXIS_NEAR."""
    t = mesh.topology
    N = np.array([_newell(mesh.V[f[f >= 0]]) for f in mesh.F])
    X = np.zeros((mesh.n_vertices, 3))
    for v in range(mesh.n_vertices):
        faces = t.star_faces[v][t.star_faces[v] >= 0]
        x = np.linalg.lstsq(N[faces], np.ones(len(faces)), rcond=AXIS_RCOND)[0]
        ang = np.arccos(np.clip(N[faces] @ (x / np.linalg.norm(x)), -1, 1))
        if 0.5 * (ang.max() - ang.min()) < NEAR_CONICAL:
            x = np.linalg.lstsq(N[faces], np.ones(len(faces)), rcond=AXIS_NEAR)[0]
        X[v] = x
    return N, X


def reference_twist(P0, P1, P2, P3):
    """Distance between the diagonal lines P0P2, P1P3, and the dihedral angle about P0P1 (deg)."""
    d1, d2 = P2 - P0, P3 - P1
    n = np.cross(d1, d2)
    mm = abs(np.dot(P1 - P0, n)) / np.linalg.norm(n)
    e = (P1 - P0) / np.linalg.norm(P1 - P0)
    pa = (P3 - P0) - np.dot(P3 - P0, e) * e
    pb = (P2 - P1) - np.dot(P2 - P1, e) * e
    cosang = np.dot(pa, pb) / (np.linalg.norm(pa) * np.linalg.norm(pb))
    ang = np.degrees(np.arccos(np.clip(cosang, -1, 1)))
    return mm, ang * np.sign(np.dot(e, np.cross(pa, pb)))


# -- PQ, not conical: the report quantifies the failure ------------------------------------------
def test_non_conical_pq_mesh_twist_and_face_errors_match_a_direct_computation():
    m = translational()
    assert planarity(m).max() <= 1e-12 and conical_defect(m).max() > 1e-2
    s = offset_structure(m, DIST, free_axes="min_norm")
    assert not s.is_conical and s.report["status"] == "pq_not_conical"
    N, X = reference_offsets(m)
    d0, d1 = s.beam_span
    assert (d0, d1) == (0.0, 120.0)
    for e, (a, b) in enumerate(s.edges):
        P = [m.V[a] + d0 * X[a], m.V[b] + d0 * X[b], m.V[b] + d1 * X[b], m.V[a] + d1 * X[a]]
        mm, deg = reference_twist(*P)
        assert s.beam_twist_mm[e] == pytest.approx(mm, rel=1e-6, abs=1e-9)
        assert s.beam_twist_deg[e] == pytest.approx(deg, rel=1e-6, abs=1e-9)
    for f, row in enumerate(m.F):
        idx = row[row >= 0]
        for i, d in enumerate(DIST):
            h = [(d * X[v]) @ N[f] for v in idx]
            assert s.face_distance_error[f, i] == pytest.approx(max(abs(x - d) for x in h), abs=1e-9)
    # genuinely non-zero, and named in the report and the sentences
    assert s.beam_twist_mm.max() > 0.1 and s.face_distance_error.max() > 1e-3
    worst = s.report["beams"]["worst"][0]
    assert worst["edge"] == int(np.argmax(s.beam_twist_mm))
    assert worst["twist_mm"] == pytest.approx(s.beam_twist_mm.max())
    assert s.report["face_distance"]["worst"][0]["face"] == int(np.argmax(s.face_distance_error.max(axis=1)))
    text = " ".join(s.report["summary"])
    assert "NOT CONICAL" in text and "twist" in text and "mm" in text


def test_planar_beam_axes_only_change_free_vertices():
    from fabricate.offset.axes import face_planes, fit_axes

    m = translational()
    s = offset_structure(m, DIST, free_axes="min_norm")
    p = offset_structure(m, DIST)
    t = m.topology
    inner = ~t.is_boundary_vertex
    fit = fit_axes(m, face_planes(m)[0])
    fixed = inner & (fit.free_rank == 0)
    assert fixed.any()
    np.testing.assert_array_equal(p.axes[fixed], s.axes[fixed])
    boundary = t.is_boundary_vertex[p.edges].all(axis=1)
    # the mesh is not conical: its beams inside twist, so turning the free axes is a least-squares
    # compromise, and the boundary beams come out planar to a few 1e-6 mm (from 0.1 mm and more)
    assert p.beam_twist_mm[boundary].max() < 1e-5 and s.beam_twist_mm[boundary].max() > 1e-2
    # free directions move face distances by at most AXIS_NEAR of the turn (exactly 0 for k < 3)
    turn = np.linalg.norm(p.offset - s.offset, axis=1).max()  # the largest change of an offset vector
    assert np.abs(p.face_distance_error - s.face_distance_error).max() <= 1e-9 + AXIS_NEAR * max(DIST) * turn


# -- the paper's Remark: a PQ mesh with the offset property is conical ---------------------------
def _offset_planes_meet(mesh, d=100.0):
    """Loop: per interior valence-4 vertex, the residual of the least-squares point of its four
    face planes moved by ``d`` (zero exactly when an offset vertex at face distance d exists)."""
    t = mesh.topology
    out = []
    for v in t.interior_valence4:
        faces = t.star_faces[v][:4]
        A, rhs = [], []
        for f in faces:
            idx = mesh.F[f][mesh.F[f] >= 0]
            n = _newell(mesh.V[idx])
            A.append(n)
            rhs.append(n @ mesh.V[idx].mean(axis=0) + d)
        A, rhs = np.array(A), np.array(rhs)
        x = np.linalg.lstsq(A, rhs, rcond=None)[0]
        out.append(np.abs(A @ x - rhs).max() / d)
    return np.array(out)


@pytest.mark.parametrize("case", ["translational_mixed", "pq_dome"])
def test_remark_offset_property_holds_exactly_at_the_conical_vertices(case):
    if case == "translational_mixed":
        m = translational(b_flat_until=0.5)
    else:  # a PQ (not conical) mesh from the optimizer
        noisy = shapes.perturbed(shapes.revolution(shapes.dome_profile(10, 4, 7), 12), 0.05, seed=2)
        res = optimize_mesh(noisy, "pq", tol=Tolerances(planarity=1e-13))
        assert res.success, res.message
        m = res.mesh
    assert planarity(m).max() <= 1e-12
    meet = _offset_planes_meet(m)
    cone = conical_defect(m)
    offset_property = meet <= 1e-9
    is_conical = cone <= 1e-9
    assert np.array_equal(offset_property, is_conical)
    if case == "translational_mixed":
        assert offset_property.any() and not offset_property.all()
    else:
        assert not offset_property.any()
    # and the stage: its face-distance error vanishes exactly around conical vertices
    s = offset_structure(m, (100.0,))
    t = m.topology
    err = s.face_distance_error[:, 0]
    for k, v in enumerate(t.interior_valence4):
        faces_err = err[t.star_faces[v][:4]].max()
        if not is_conical[k]:
            assert s.axis_defect[v] > 1e-6
        if is_conical[k] and np.all(np.isin(t.star_neighbors[v][:4], t.interior_valence4[is_conical])):
            assert faces_err <= 1e-9 * 100  # all corners of its faces conical: faces exactly offset


def test_remark_on_whole_meshes():
    """Offset property (every face exactly d) holds for the conical dome, fails for a PQ mesh."""
    dome = shapes.revolution(shapes.dome_profile(10, 4, 7), 12)
    tr = translational()
    assert offset_structure(dome, (1.0,)).face_distance_error.max() <= 1e-9
    assert offset_structure(tr, (100.0,)).face_distance_error.max() > 1e-3
    assert conical_defect(dome).max() <= 1e-9 < conical_defect(tr).max()


# -- focal meshes ---------------------------------------------------------------------------------
def test_focal_points_of_a_surface_of_revolution():
    m = shapes.revolution(shapes.dome_profile(8000, 3000, 7), 16)
    s = offset_structure(m, DIST)
    fm = focal_meshes(m, s.axes)
    assert (fm.family >= 0).all() and set(np.unique(fm.family)) == {0, 1}
    assert fm.gap.max() <= 1e-9 * m.bbox_diagonal()
    # parallels: axes of neighbours on a parallel meet on the rotation axis (the cone apex)
    z = m.V[:, 2]
    parallel = np.isclose(z[s.edges[:, 0]], z[s.edges[:, 1]])
    assert np.abs(fm.points[parallel, :2]).max() <= 1e-6
    # meridian edges are the other family
    fam = fm.family[parallel]
    assert (fam == fam[0]).all() and (fm.family[~parallel] != fam[0]).all()
    # a focal quad has two points on each end axis of its edge: it lies in that beam plane
    ok = np.isfinite(fm.points[fm.quads]).all(axis=(1, 2))
    assert ok.sum() > 0
    Q = fm.points[fm.quads[ok]]
    assert quad_planarity(Q).max() <= 1e-6
    n = s.beam_normals[fm.quad_edge[ok]]
    p0 = m.V[s.edges[fm.quad_edge[ok], 0]]
    dist = np.abs(np.einsum("qkj,qj->qk", Q - p0[:, None, :], n))
    assert dist.max() <= 1e-9 * np.abs(Q).max()
    # vertices of a focal quad belong to one family, the quad's edge to the other
    assert (fm.family[fm.quads] == fm.quad_family[:, None]).all()
    assert (fm.family[fm.quad_edge] != fm.quad_family).all()


def test_axis_line_intersections_by_hand():
    V = np.array([[0.0, 0, 0], [2.0, 0, 0], [0, 0, 0], [0, 1, 0]])
    axes = np.array([[1.0, 1, 0] / np.sqrt(2), [-1.0, 1, 0] / np.sqrt(2), [0, 0, 1.0], [0, 0, 1.0]])
    P, radii, gap = axis_line_intersections(V, axes, np.array([[0, 1], [2, 3]]))
    np.testing.assert_allclose(P[0], [1, 1, 0], atol=1e-15)  # the lines meet at (1, 1, 0)
    np.testing.assert_allclose(radii[0], [np.sqrt(2), np.sqrt(2)], rtol=1e-15)
    assert gap[0] == 0.0
    assert np.isnan(P[1]).all() and np.isinf(radii[1]).all() and gap[1] == 0.0  # parallel: coplanar
    skew = np.array([[0.0, 0, 1], [1.0, 0, 0]])
    _, _, g = axis_line_intersections(np.array([[0.0, 0, 0], [0, 3.0, 0]]), skew, np.array([[0, 1]]))
    assert g[0] == pytest.approx(3.0)


def test_edge_families_fail_on_an_odd_cycle(cylinder_path):
    from optimize.mesh.io import read_mesh

    grid = shapes.grid(4, 5)
    fam = edge_families(grid)
    horizontal = np.isclose(grid.V[grid.topology.edges[:, 0], 1], grid.V[grid.topology.edges[:, 1], 1])
    assert len(set(fam[horizontal])) == 1 and len(set(fam[~horizontal])) == 1
    assert fam[horizontal][0] != fam[~horizontal][0]
    # three quads around an interior valence-3 vertex: no two-colouring of the strips there
    V = np.array([[0, 0, 0], [1, 0, 0], [0.5, 0.9, 0], [-0.5, 0.9, 0], [-1, 0, 0], [-0.5, -0.9, 0],
                  [0.5, -0.9, 0.0]])
    from optimize import Mesh

    m = Mesh(V, [[0, 1, 2, 3], [0, 3, 4, 5], [0, 5, 6, 1]])
    assert (edge_families(m) == -1).any()
    assert (edge_families(read_mesh(cylinder_path)) >= 0).all()


def test_quad_circular_defect_by_hand():
    a = np.radians([10, 80, 200, 300])
    circle = np.stack([np.cos(a), np.sin(a), 0 * a], axis=1)[None]
    assert quad_circular_defect(circle)[0] <= 1e-14
    kite = np.array([[[0, 0, 0], [1, 0, 0], [1.5, 1, 0], [0, 1, 0]]], dtype=float)
    assert quad_circular_defect(kite)[0] > 0.1
    assert np.isnan(quad_circular_defect(np.array([[[0, 0, 0], [0, 0, 0], [1, 1, 0], [0, 1, 0.0]]]))[0])


# -- input checks ----------------------------------------------------------------------------------
def test_require_pq_names_the_worst_faces():
    noisy = shapes.perturbed(translational(), 0.02, seed=4)
    p = planarity(noisy)
    worst = int(np.argmax(p))
    with pytest.raises(MeshError, match=rf"worst face {worst} .*{p[worst]:.3g}") as exc:
        require_pq(noisy)
    assert "expected a PQ mesh" in str(exc.value)
    require_pq(translational())  # PQ: no error
    s = offset_structure(noisy, DIST)  # the library itself reports instead of refusing
    assert s.report["status"] == "not_pq" and not s.report["is_pq"]
    assert s.report["planarity"]["worst"][0]["face"] == worst
    assert "NOT PQ" in s.report["summary"][0]


def test_planar_beam_jacobian_matches_finite_differences():
    from fabricate.offset.axes import face_planes, fit_axes
    from fabricate.offset.straighten import FreeAxes

    m = translational()
    fit = fit_axes(m, face_planes(m)[0])
    prob = FreeAxes(m.V, m.topology.edges, fit)
    assert prob.n_par > 0 and len(prob.E) > 0
    p = 0.1 * np.random.default_rng(0).standard_normal(prob.n_par)
    J = prob.jacobian(p).toarray()
    h = 1e-6
    I = np.eye(prob.n_par)
    fd = np.stack([(prob.residual(p + h * I[k]) - prob.residual(p - h * I[k])) / (2 * h)
                   for k in range(prob.n_par)], axis=1)
    np.testing.assert_allclose(J, fd, atol=1e-8)
    # the free directions keep every face distance: n_i . (X + B p) = n_i . X
    X, N = prob.offsets(p), face_planes(m)[0]
    t = m.topology
    for v in np.nonzero(fit.free_rank > 0)[0]:  # exactly, or within AXIS_RCOND of the turn when nearly free
        faces = t.star_faces[v][t.star_faces[v] >= 0]
        turn = np.linalg.norm(X[v] - fit.offset[v])
        np.testing.assert_allclose(N[faces] @ X[v], N[faces] @ fit.offset[v], atol=1e-12 + AXIS_NEAR * turn)
