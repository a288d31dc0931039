"""Offset stage: exact constant-distance layers, conical offsets, planar beams, invariance.

Meshes that are conical by construction (surfaces of revolution, the capped
cylinder), conical meshes from the optimizer, and a translational surface
(PQ, not conical).  Model units are mm (meshes a few metres across).
"""
from __future__ import annotations

import numpy as np
import pytest

from fabricate.offset import (beam_planarity, fit_axes, face_planes, offset_structure,
                              spherical_image_defect)
from optimize import Mesh, Tolerances
from optimize.modelling import shapes
from optimize.api import optimize_mesh
from optimize.errors import ConfigError, MeshError
from optimize.mesh.io import read_mesh
from optimize.mesh.measures import conical_defect, face_normals, planarity, quad_planarity

DIST = (0.0, 20.0, 120.0)
REL = 1e-9


def dome(n_around=16, sweep=2 * np.pi, name="dome"):
    return shapes.revolution(shapes.dome_profile(radius=8000.0, rise=3000.0, k=7), n_around,
                             sweep=sweep, name=name)


def translational(name="translational"):
    u = np.linspace(0.0, 1.0, 8)
    a = np.stack([6000 * u, 0 * u, 1500 * np.sin(2 * u)], axis=1)
    b = np.stack([0 * u, 5000 * u, 900 * np.cos(2.5 * u)], axis=1)
    return shapes.translational(a, b, name=name)


@pytest.fixture(scope="module")
def optimized():
    """A conical mesh from the optimizer (a noisy saddle-dome height field), in mm."""
    m0 = shapes.grid(7, 6, (6.0, 5.0), height=lambda x, y: 0.08 * (x - 3) ** 2 - 0.05 * (y - 2.5) ** 2
                     + 0.02 * x * y, name="saddle")
    m0 = shapes.perturbed(m0, 0.02, seed=3)
    res = optimize_mesh(m0, "conical", tol=Tolerances(planarity=1e-13, conical=1e-13))
    assert res.success, res.message
    return res.mesh.with_vertices(res.mesh.V * 1000.0, name="optimized"), res


@pytest.fixture(scope="module")
def optimized_dome():
    """A noisy dome of revolution made conical again by the optimizer."""
    res = optimize_mesh(shapes.perturbed(dome(12), 0.03, seed=5), "conical",
                        tol=Tolerances(planarity=1e-13, conical=1e-13))
    assert res.success, res.message
    return res.mesh.with_vertices(res.mesh.V, name="optimized_dome")


def conical_meshes(request):
    name = request.param
    if name == "dome":
        return dome()
    if name == "open_dome":
        return dome(9, sweep=np.pi, name="open_dome")
    if name == "cylinder":
        return read_mesh(request.getfixturevalue("cylinder_path"))
    if name == "optimized":
        return request.getfixturevalue("optimized")[0]
    return request.getfixturevalue("optimized_dome")


@pytest.fixture(params=["dome", "open_dome", "cylinder", "optimized", "optimized_dome"])
def conical(request):
    return conical_meshes(request)


# -- constant face distance, conical offsets ----------------------------------------------------
def test_every_offset_face_lies_exactly_d_from_its_original(conical):
    s = offset_structure(conical, DIST)
    assert s.is_conical, s.report["summary"]
    N = face_normals(conical)
    F = conical.F
    for d, layer in zip(DIST, s.layers):
        lm = conical.with_vertices(layer)
        # the offset face is parallel (same unit normal) and planar
        assert np.abs(face_normals(lm) - N).max() <= REL
        assert planarity(lm).max() <= REL
        # every corner of the offset face is d above the original face plane
        for f in range(conical.n_faces):  # a direct loop, the reference
            idx = F[f][F[f] >= 0]
            h = (layer[idx] - conical.V[idx]) @ N[f]
            assert np.abs(h - d).max() <= REL * max(abs(d), 1.0), (f, h, d)
    assert s.face_distance_error.max() <= REL * max(DIST)
    assert s.report["face_distance"]["ok"] and s.report["status"] == "conical"


def test_offsets_are_conical_with_the_same_axes(conical):
    s = offset_structure(conical, DIST)
    for i, d in enumerate(DIST):
        lm = s.layer_mesh(i)
        assert conical_defect(lm).max(initial=0.0) <= 1e-9
        again = offset_structure(lm, (10.0,))
        assert again.is_conical
        # the faces are parallel, so the axis of every vertex that has three independent
        # face normals is the same, and offsetting the offset adds the distances; free
        # (boundary) axes are turned for planar beams of each mesh and may differ
        determined = fit_axes(conical, face_planes(conical)[0]).free_rank == 0
        assert determined.sum() > 0
        assert np.abs(again.axes - s.axes)[determined].max() <= 1e-9
        np.testing.assert_allclose(again.layers[0][determined],
                                   (conical.V + (d + 10.0) * s.offset)[determined],
                                   rtol=0, atol=1e-9 * conical.bbox_diagonal())


def test_neighbouring_axes_are_coplanar_so_beams_are_planar(conical):
    s = offset_structure(conical, DIST)
    # Geometry Fact 2: where both axes are cone axes, the beam is planar
    free = fit_axes(conical, face_planes(conical)[0]).free_rank > 0
    fixed = ~free[s.edges].any(axis=1)
    assert fixed.sum() > 0
    assert beam_planarity(s.beam_quads[fixed]).max() <= REL
    assert quad_planarity(s.beam_quads[fixed]).max() <= REL  # the package's own measure
    if conical.name == "optimized_dome" and s.report["free_axes"]["regularization"] > 0:
        # a closed boundary loop without symmetry: the free boundary axes may have no exact
        # planar-beam solution nearby; the compromise leaves a small twist, reported.  (Since the
        # optimizer's fairness weight falls with the defect, this dome's result has an exact one:
        # boundary twist 3e-12 mm, checked below like the others.)
        info = s.report["free_axes"]
        assert info["regularization"] > 0 and info["residual_after"] < info["residual_before"] / 50
        bmax = s.report["beams"]["boundary_max_twist_mm"]
        assert bmax == pytest.approx(s.beam_twist_mm.max()) and 0 < bmax < 1e-2
        b = s.report["beams"]
        assert b["max_planarity"] > 1e-12 and b["ok"] == (b["max_planarity"] <= b["tolerance"])
        return
    assert beam_planarity(s.beam_quads).max() <= REL
    assert s.beam_twist_mm.max() <= REL * conical.bbox_diagonal()
    assert np.abs(s.beam_twist_deg).max() <= 1e-7
    assert s.report["beams"]["ok"]
    # beam quads run along the axes: side a@d0 -> a@d1 is parallel to the node axis
    a, _ = s.edges.T
    side = s.beam_quads[:, 3] - s.beam_quads[:, 0]
    np.testing.assert_allclose(np.cross(side, s.axes[a]), 0.0, atol=1e-9 * np.abs(side).max())
    # beam normals are perpendicular to the beam quads
    for k in range(4):
        e = s.beam_quads[:, k] - s.beam_quads[:, 0]
        assert np.abs(np.einsum("ij,ij->i", e, s.beam_normals)).max() <= 1e-9 * conical.bbox_diagonal()


def test_spherical_image_is_circular(conical):
    s = offset_structure(conical, DIST)
    d = spherical_image_defect(conical, s.normals)
    if "cylinder" not in conical.name:
        assert not np.isnan(d).any(), "doubly curved meshes have no degenerate spherical quads"
        assert d.size > 0
    assert np.nanmax(d, initial=0.0) <= 1e-9
    # and the normals around a vertex lie on the circle of centre a_v, radius theta_v
    t = conical.topology
    for v in range(conical.n_vertices):
        faces = t.star_faces[v][t.star_faces[v] >= 0]
        np.testing.assert_allclose(s.normals[faces] @ s.axes[v], s.cos_theta[v], atol=1e-12)


def test_axes_point_to_the_normals_side_and_flip_reverses(conical):
    s = offset_structure(conical, DIST)
    assert (s.cos_theta > 0).all() and (s.cos_theta <= 1 + 1e-15).all()
    f = offset_structure(conical, DIST, flip=True)
    np.testing.assert_allclose(f.normals, -s.normals, atol=0)
    np.testing.assert_allclose(f.axes, -s.axes, atol=1e-12)
    np.testing.assert_allclose(f.layers[2], conical.V - 120.0 * s.offset, atol=1e-9 * conical.bbox_diagonal())


def test_optimizer_axes_can_be_given(optimized):
    mesh, res = optimized
    assert res.axes is not None
    s = offset_structure(mesh, DIST)
    g = offset_structure(mesh, DIST, axes=res.axes)
    inner = mesh.topology.interior_valence4
    assert np.abs(g.axes[inner] - s.axes[inner]).max() <= 1e-9
    assert g.face_distance_error.max() <= REL * max(DIST)
    assert g.report["axes_source"] == "given"
    with pytest.raises(MeshError, match=r"shape \(3, 3\)"):
        offset_structure(mesh, DIST, axes=np.eye(3))
    nan_rows = np.array(res.axes)
    nan_rows[inner[:3]] = np.nan  # rows left out are fitted
    h = offset_structure(mesh, DIST, axes=nan_rows)
    assert np.abs(h.axes[inner] - s.axes[inner]).max() <= 1e-9


# -- free axes: boundary beams -------------------------------------------------------------------
def test_free_boundary_axes_are_turned_to_make_boundary_beams_planar():
    m = dome(9, sweep=np.pi, name="open_dome")
    bis = offset_structure(m, DIST, free_axes="min_norm")
    straight = offset_structure(m, DIST)
    boundary = m.topology.is_boundary_vertex[straight.edges].all(axis=1)
    # bisector axes on the boundary meridians twist their beams; the turned ones do not
    assert bis.beam_twist_mm[boundary].max() > 1e-3
    assert straight.beam_twist_mm.max() <= REL * m.bbox_diagonal()
    assert straight.report["free_axes"]["status"] == "converged"
    # both keep every face exactly at its distance (free directions do not move any face plane)
    assert bis.face_distance_error.max() <= REL * 120 and straight.face_distance_error.max() <= REL * 120
    with pytest.raises(ConfigError, match="free_axes"):
        offset_structure(m, DIST, free_axes="sideways")


# -- irregular vertices, degenerate stars ----------------------------------------------------------
def _pyramid(n=5, h=1.0, noise=0.0, seed=0):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.stack([np.cos(a), np.sin(a), 0 * a], axis=1)
    ring += noise * np.random.default_rng(seed).standard_normal(ring.shape)
    V = np.vstack([[[0.0, 0.0, h]], ring])
    return Mesh(V, [[0, 1 + i, 1 + (i + 1) % n] for i in range(n)], name="pyramid")


def test_valence_five_vertex_on_a_cone_is_exact_and_a_perturbed_one_reports_its_defect():
    m = _pyramid(5)
    s = offset_structure(m, (1.0,))
    np.testing.assert_allclose(s.axes[0], [0, 0, 1], atol=1e-12)
    r_in = np.cos(np.pi / 5)  # distance of the base edges from the axis
    np.testing.assert_allclose(s.cos_theta[0], r_in / np.hypot(r_in, 1.0), rtol=1e-12)
    assert s.axis_defect[0] <= 1e-12 and s.is_conical
    p = offset_structure(_pyramid(5, noise=0.05, seed=1), (1.0,))
    N = p.normals
    ang = np.arccos(np.clip(N @ p.axes[0], -1, 1))
    assert p.axis_defect[0] == pytest.approx(0.5 * (ang.max() - ang.min()), rel=1e-6)
    assert p.axis_defect[0] > 1e-3 and not p.is_conical
    assert p.report["axis_defect_rad"]["worst"][0]["vertex"] == 0


def test_flat_and_cylindrical_stars_use_the_normal_and_the_bisector():
    g = shapes.grid(5, 4, (4000.0, 3000.0))
    s = offset_structure(g, (50.0,))
    np.testing.assert_allclose(s.axes, np.tile([0, 0, 1.0], (g.n_vertices, 1)), atol=1e-15)
    np.testing.assert_allclose(s.layers[0], g.V + [0, 0, 50.0], atol=1e-9)
    cyl = shapes.revolution(np.array([[3000.0, z] for z in np.linspace(0, 4000, 5)]), 12, name="cyl")
    c = offset_structure(cyl, (100.0,))
    radial = cyl.V[:, :2] / np.linalg.norm(cyl.V[:, :2], axis=1, keepdims=True)
    np.testing.assert_allclose(c.axes[:, :2], radial, atol=1e-12)
    np.testing.assert_allclose(c.axes[:, 2], 0, atol=1e-12)
    assert c.is_conical and c.face_distance_error.max() <= REL * 100
    assert c.beam_twist_mm.max() <= 1e-9


def test_nearly_cylindrical_conical_vertices_keep_their_beams_planar(monkeypatch):
    """A cylinder of circles and rulings (radius 1 m) moved by 1e-5 mm: conical to 4e-7 rad, within the
    default tolerance, but the cone axis at each vertex is ill-conditioned (the normals nearly span a
    plane).  The exact least-squares axes tilt along the rulings and twist the beams by about 76 mm;
    counting the near-free direction as free (AXIS_NEAR) lets the beams be straightened (3e-6 mm)
    while face distances stay within 1e-5 mm."""
    import fabricate.offset.axes as axes_mod

    th, y = np.linspace(0, np.pi, 13), np.linspace(0.0, 3000.0, 11)
    T, Y = np.meshgrid(th, y, indexing="ij")
    V = np.stack([1000 * np.cos(T), Y, 1000 * np.sin(T)], -1).reshape(-1, 3)
    n = len(y)
    F = [[i * n + j, i * n + j + 1, (i + 1) * n + j + 1, (i + 1) * n + j] for i in range(len(th) - 1)
         for j in range(n - 1)]
    V = V + 1e-5 * np.random.default_rng(3).standard_normal(V.shape)
    mesh = Mesh(V, F, name="cylinder")
    assert conical_defect(mesh).max() < 1e-6
    interior = ~mesh.topology.is_boundary_vertex[mesh.topology.edges].any(axis=1)
    s = offset_structure(mesh, (0.0, -200.0))
    monkeypatch.setattr(axes_mod, "AXIS_NEAR", axes_mod.AXIS_RCOND)  # the exact least-squares axes
    exact = offset_structure(mesh, (0.0, -200.0))
    assert s.beam_twist_mm[interior].max() < 1e-4 and exact.beam_twist_mm[interior].max() > 1.0
    assert s.face_distance_error.max() < 1e-5


def test_non_orientable_mesh_is_refused():
    k = 12
    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    V = []
    for ti in t:
        for s in (-1.0, 1.0):
            rad = 1 + 0.3 * s * np.cos(ti / 2)
            V.append([rad * np.cos(ti), rad * np.sin(ti), 0.3 * s * np.sin(ti / 2)])
    F = [[2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1] for i in range(k - 1)] + [[2 * k - 2, 1, 0, 2 * k - 1]]
    m = Mesh(np.array(V), F, name="moebius")
    assert not m.topology.orientable
    with pytest.raises(MeshError, match="not orientable"):
        offset_structure(m, DIST)


def test_bad_distances_are_config_errors():
    m = dome(8)
    for bad, pattern in (([], "none given"), ([0, 20, 20], "given twice"), ([0, np.inf], "not finite"),
                         ([0], "single zero"), (["a"], "expected numbers")):
        with pytest.raises(ConfigError, match=pattern):
            offset_structure(m, bad)
    one = offset_structure(m, (120.0,))
    assert one.beam_span == (0.0, 120.0)  # one distance: beams from the mesh to that layer
    np.testing.assert_allclose(one.beam_quads[:, 0], m.V[one.edges[:, 0]], atol=0)


# -- purity and invariance -------------------------------------------------------------------------
def test_inputs_are_not_mutated(optimized):
    mesh, res = optimized
    V, F = mesh.V.copy(), mesh.F.copy()
    axes = np.array(res.axes)
    axes_copy = axes.copy()
    edges_before = mesh.topology.edges.copy()
    s = offset_structure(mesh, [0, 20, 120], axes=axes)
    offset_structure(mesh, DIST, flip=True)
    assert np.array_equal(mesh.V, V) and np.array_equal(mesh.F, F)
    assert np.array_equal(axes, axes_copy) and np.array_equal(mesh.topology.edges, edges_before)
    assert mesh.topology.edges.flags.writeable == edges_before.flags.writeable
    assert not s.layers[0].flags.writeable and not s.axes.flags.writeable
    with pytest.raises(Exception):
        s.is_conical = False  # frozen


@pytest.mark.parametrize("make", [dome, translational])
def test_rigid_motion_and_scale(make, rotation):
    m = make()
    R, shift = rotation(11), np.array([1234.0, -567.0, 89.0])
    s = offset_structure(m, DIST)
    r = offset_structure(m.with_vertices(m.V @ R.T + shift), DIST)
    L = m.bbox_diagonal()
    np.testing.assert_allclose(r.axes, s.axes @ R.T, atol=1e-9)
    np.testing.assert_allclose(r.cos_theta, s.cos_theta, atol=1e-12)
    for a, b in zip(r.layers, s.layers):
        np.testing.assert_allclose(a, b @ R.T + shift, atol=1e-9 * L)
    np.testing.assert_allclose(r.beam_twist_mm, s.beam_twist_mm, atol=1e-9 * L)
    np.testing.assert_allclose(r.beam_twist_deg, s.beam_twist_deg, atol=1e-7)
    np.testing.assert_allclose(r.face_distance_error, s.face_distance_error, atol=1e-9 * L)
    assert r.is_conical == s.is_conical
    # scaling the mesh by k scales lengths, keeps angles; distances scaled too give the same shape
    k = 2.5
    z = offset_structure(m.with_vertices(k * m.V), tuple(k * d for d in DIST))
    np.testing.assert_allclose(z.layers[2], k * s.layers[2], atol=1e-9 * k * L)
    np.testing.assert_allclose(z.beam_twist_mm, k * s.beam_twist_mm, atol=1e-9 * k * L)
    np.testing.assert_allclose(z.beam_twist_deg, s.beam_twist_deg, atol=1e-7)
