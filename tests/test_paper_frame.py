"""What makes the paper's methods move with their input (issue 31 item 5).

- the canonical frame (:mod:`optimize.solvers.paper.frame`) turns with the mesh, also where
  the principal axes are not unique (a surface of revolution, a symmetric cloud);
- the reference's vertex normals at a Moebius band's seam are normals (they cancelled to a
  direction rounding chose), and interpolate without passing through zero;
- closest-point ties (a point on a symmetry plane between two triangles) are broken by the
  lowest triangle index in every search, whatever the rounding.
The methods' invariance itself is ``tests/test_optimize_contract.py``'s.
"""
import numpy as np
import pytest

from optimize import kernels
from optimize.mesh import Mesh
from optimize.modelling import shapes
from optimize.modelling.designs import trefoil_band_mesh
from optimize.proximity.footpoints import Footpoints
from optimize.proximity.surface import Reference
from optimize.solvers.paper.frame import canonical_rotation
from optimize.solvers.paper.problem import Problem

ROT = np.linalg.qr(np.random.default_rng(13).standard_normal((3, 3)))[0]  # det +1 (checked below)


def _clouds():
    dome = shapes.revolution(shapes.dome_profile(k=4), 8)  # horizontal axes: any pair (8-fold symmetric)
    yield "perturbed dome", shapes.perturbed(dome, 0.03, seed=5).V
    yield "dome", dome.V
    yield "trefoil band", trefoil_band_mesh(24, 0.4).V
    cube = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=float)
    yield "cube corners", cube  # isotropic and centrally symmetric: every rule falls back to indices


@pytest.mark.parametrize("name,V", list(_clouds()), ids=lambda v: v if isinstance(v, str) else "")
def test_canonical_frame_turns_with_the_cloud(name, V):
    assert np.linalg.det(ROT) > 0
    X = V - V.mean(axis=0)
    R = canonical_rotation(X)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-14)
    assert np.linalg.det(R) > 0  # a rotation: the strip determinants keep their signs
    R2 = canonical_rotation(1e3 * X @ ROT.T)
    np.testing.assert_allclose(R2, ROT @ R, atol=1e-9)  # the same axes, turned
    np.testing.assert_allclose(X @ R, (X @ ROT.T) @ R2, atol=1e-9 * np.abs(X).max())


def test_canonical_frame_keeps_a_roofs_axes():
    """An input whose principal axes are the model's keeps them (up to order and sign), so the
    per-coordinate damping acts as before on roofs modelled with z up."""
    m = shapes.perturbed(shapes.grid(6, 4, size=(6.0, 4.0)), 0.02, seed=1)
    R = canonical_rotation(m.V - m.V.mean(axis=0))
    np.testing.assert_allclose(np.abs(R), np.eye(3), atol=0.05)


def test_problem_solves_in_the_canonical_frame():
    m = shapes.perturbed(shapes.revolution(shapes.dome_profile(k=4), 8), 0.03, seed=5)
    moved = m.with_vertices(1e-3 * m.V @ ROT.T + [100.0, -50.0, 7.0])
    p, q = Problem(m, "pq"), Problem(moved, "pq")
    np.testing.assert_allclose(q.x0(), p.x0(), atol=1e-9)  # the solver's input: rounding apart
    np.testing.assert_allclose(p.positions(p.x0()), m.V, atol=1e-13)


def test_moebius_seam_vertex_normals_are_normals():
    """The trefoil band's faces run its seam edge the same way: summed as they were, the triangle
    normals at the seam's ends cancelled to 1e-15 and normalizing gave a direction rounding chose."""
    m = trefoil_band_mesh(24, 0.4)
    assert not m.topology.orientable
    ref = Reference(m)
    T, n = ref.triangles, ref.normals
    for v in range(m.n_vertices):
        around = n[np.any(T == v, axis=1)]
        assert np.abs(around @ ref.vertex_normals[v]).min() > 0.5, v  # along every triangle's normal
    # interpolated over any triangle the normals face the triangle's own: no zero on the way
    rng = np.random.default_rng(2)
    w = rng.dirichlet(np.ones(3), size=len(T))
    Y = np.einsum("tj,tjk->tk", w, m.V[T])
    N = ref._interpolated_normals(Y, np.arange(len(T)))
    assert np.einsum("tk,tk->t", N, n).min() > 0.5


def test_orientable_reference_normals_unchanged():
    m = shapes.perturbed(shapes.revolution(shapes.dome_profile(k=4), 8), 0.03, seed=5)
    ref = Reference(m)
    assert ref.normal_corners is ref.triangles and ref.normal_table is ref.vertex_normals


def _crease():
    """Two triangles meeting at a concave crease along the y axis, mirror images under x -> -x
    (triangle 1 is the mirror of triangle 0), and points on the mirror plane above the crease."""
    V = np.array([[0.0, 0, 0], [0, 1, 0], [-1, 0.5, 1], [1, 0.5, 1]])
    m = Mesh(V, np.array([[1, 0, 2], [0, 1, 3]]))
    P = np.array([[x, 0.5, 0.4] for x in (1e-17, -1e-17, 3e-16, -3e-16, 0.0)])
    return m, P


@pytest.mark.parametrize("path", ["reference", "footpoints-numpy", "footpoints-compiled"])
def test_closest_point_ties_go_to_the_lowest_triangle(path):
    m, P = _crease()
    ref = Reference(m)
    _, _, tri = ref.closest(np.array([[0.3, 0.5, 0.4], [-0.3, 0.5, 0.4]]), return_index=True)
    assert tri.tolist() == [1, 0]  # off the plane each side has its own triangle
    if path == "reference":
        Y, N, tri = ref.closest(P, return_index=True)
    else:
        if path == "footpoints-compiled" and kernels.get() is None:
            pytest.skip("numba not installed")
        foot = Footpoints(ref, 0.1, compiled=path == "footpoints-compiled")
        Y, N = foot.closest(P)
        tri = foot.tri
        Y2, N2 = foot.closest(P[::-1].copy())  # warm: the last answers are tested first
        np.testing.assert_array_equal(Y2, Y[::-1])
    assert tri.tolist() == [0] * len(P)  # on the plane: the tie, whatever the rounding
    np.testing.assert_allclose(Y, Y[:1].repeat(len(P), 0), atol=1e-15)
