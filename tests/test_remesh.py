"""Remeshing a triangle surface along principal curvature lines, and the chain to a conical mesh."""
from __future__ import annotations

import numpy as np
import pytest

from optimize import ConfigError, Mesh, MeshError, Tolerances, surfaces
from optimize.closeness import Reference
from optimize.isolines import planar_faces
from optimize.measures import conical_defect, planarity
from optimize.remesh import isoparametric_remesh, remesh, surface_to_mesh


@pytest.fixture(scope="module")
def waist():
    return surfaces.revolution_patch()


@pytest.fixture(scope="module")
def waist_quads(waist):
    return remesh(waist.mesh, 0.25, side=waist.side, with_report=True)


@pytest.fixture(scope="module")
def roof():
    return surfaces.height_field()


def _edge_alignment(quads, surf):
    """(e,) degrees between every inner edge and the nearer exact principal direction at its midpoint."""
    E = quads.topology.edges[~quads.topology.is_boundary_edge]
    D = quads.V[E[:, 1]] - quads.V[E[:, 0]]
    D /= np.linalg.norm(D, axis=1, keepdims=True)
    Y, _ = Reference(surf.mesh).closest(0.5 * (quads.V[E[:, 0]] + quads.V[E[:, 1]]))
    d1, d2, _, _, _ = surf.exact(Y)
    c = np.maximum(np.abs(np.einsum("ij,ij->i", D, d1)), np.abs(np.einsum("ij,ij->i", D, d2)))
    return np.degrees(np.arccos(np.clip(c, 0, 1)))


def test_surface_of_revolution_gives_meridians_and_parallels(waist, waist_quads):
    quads, rep = waist_quads
    ang = _edge_alignment(quads, waist)
    assert ang.mean() < 2.0 and ang.max() < 8.0, (ang.mean(), ang.max())
    assert rep.singular_triangles == 0 and rep.folded == 0
    sizes = quads.face_sizes
    assert np.mean(sizes == 4) > 0.9
    # vertices lie on the input surface
    assert Reference(waist.mesh).distance(quads.V).max() < 1e-9 * waist.mesh.bbox_diagonal()
    # edge length near the target (principal lines spread a little)
    assert 0.85 * 0.25 < rep.edge_length["mean"] < 1.1 * 0.25
    # quads are nearly planar already: a principal net is a conjugate net
    assert np.median(planarity(quads)[sizes == 4]) < 5e-3


def test_faces_are_oriented_like_the_surface_and_non_quads_touch_the_boundary(roof):
    quads = remesh(roof.mesh, 0.3, side=roof.side)
    t = quads.topology
    from optimize.measures import face_normals

    assert np.all(face_normals(quads)[:, 2] > 0)  # outward = up for a roof
    other = np.nonzero(quads.face_sizes != 4)[0]
    touches = np.array([t.is_boundary_vertex[quads.F[f][quads.F[f] >= 0]].any() for f in other])
    assert touches.all()
    inner = ~t.is_boundary_vertex
    assert set(np.unique(t.valence[inner]).tolist()) <= {3, 4}  # 3: a T-junction inside a 5-gon
    assert len(t.boundary_loops) == 1 and t.n_components == 1


def test_remesh_is_scale_invariant_and_pure(roof):
    V0 = roof.mesh.V.copy()
    a = remesh(roof.mesh, 0.35, side=roof.side)
    big = Mesh(3.0 * roof.mesh.V, roof.mesh.F)
    b = remesh(big, 1.05, side=roof.side)
    assert np.array_equal(a.F, b.F)
    assert np.allclose(3.0 * a.V, b.V, atol=1e-9)
    assert np.array_equal(V0, roof.mesh.V)


def test_isoparametric_baseline_follows_the_axes(roof):
    grid = isoparametric_remesh(roof.mesh, 0.3)
    E = grid.topology.edges[~grid.topology.is_boundary_edge]
    D = grid.V[E[:, 1]] - grid.V[E[:, 0]]
    assert np.all(np.minimum(np.abs(D[:, 0]), np.abs(D[:, 1])) < 1e-9)
    assert np.mean(grid.face_sizes == 4) > 0.9


def test_planar_faces_of_a_small_graph():
    P = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [2, 0], [2, 1.0]])
    E = np.array([[0, 1], [1, 2], [2, 3], [0, 3], [1, 4], [4, 5], [2, 5], [0, 2]])
    F, area = planar_faces(P, E)
    assert sorted(np.round(area, 12).tolist()) == [0.5, 0.5, 1.0]
    got = {tuple(np.roll(f[f >= 0], -int(np.argmin(f[f >= 0])))) for f in F}
    assert got == {(0, 1, 2), (0, 2, 3), (1, 4, 5, 2)}


def test_bad_surfaces_raise_with_the_facts(roof):
    with pytest.raises(MeshError, match="closed surface"):
        remesh(surfaces.ellipsoid(level=2).mesh, 0.3)
    F = roof.mesh.F
    c = roof.mesh.V[F].mean(1)
    Fh = F[np.linalg.norm(c[:, :2], axis=1) > 0.5]
    used, Fh = np.unique(Fh, return_inverse=True)
    holed = Mesh(roof.mesh.V[used], Fh.reshape(-1, 3))
    with pytest.raises(MeshError, match="boundary loop"):
        remesh(holed, 0.3)
    with pytest.raises(ConfigError, match="edge length"):
        remesh(roof.mesh, 50.0)
    with pytest.raises(ConfigError, match="edge_length"):
        remesh(roof.mesh, -1.0)


def test_chain_from_triangles_to_a_conical_mesh_meets_the_tolerances(waist):
    tol = Tolerances()
    mesh, res, rep = surface_to_mesh(waist.mesh, 0.3, target="conical", side=waist.side, tol=tol)
    assert res.success, res.message
    assert conical_defect(mesh).max() <= tol.conical
    assert planarity(mesh).max() <= tol.planarity
    assert Reference(waist.mesh).distance(mesh.V).max() < 0.02 * waist.mesh.bbox_diagonal()
    assert "optimize" in rep.timings


def test_cli_remesh_writes_a_mesh(tmp_path, roof):
    from fabricate.cli import main
    from optimize.io import read_mesh, write_mesh

    src = tmp_path / "roof.obj"
    write_mesh(src, roof.mesh)
    out = tmp_path / "quads.obj"
    assert main(["remesh", str(src), "--edge-length", "0.4", "-o", str(out), "--optimize", "none",
                 "--side", "0,0,-1", "--report", str(tmp_path / "r.json")]) == 0
    quads = read_mesh(out)
    assert np.mean(quads.face_sizes == 4) > 0.85
    assert (tmp_path / "r.json").is_file()
    assert main(["remesh", str(src), "--edge-length", "0.4", "-o", str(out), "--side", "1,0,0"]) == 2
