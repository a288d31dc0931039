"""Catmull-Clark, Doo-Sabin and polyline subdivision as sparse operators.

Known values (a Catmull-Clark cube by hand), a loop-per-face reference
implementation of Catmull-Clark with boundaries, planes staying planar,
boundary curves following the cubic B-spline (CC) and Chaikin (DS) rules,
corners kept, operators that are affine combinations (rows sum to one).
"""
from __future__ import annotations

import numpy as np
import pytest

from optimize import ConfigError, Mesh, MeshError
from optimize.modelling import shapes
from optimize.modelling.curves import chaikin, curve_operator, lane_riesenfeld
from optimize.modelling.subdivision import SCHEMES, catmull_clark, doo_sabin, subdivide


def cube() -> Mesh:
    V = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    F = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    return Mesh(V, F, name="cube")


def mixed() -> Mesh:
    """Quads, a triangle and a pentagon, one boundary loop with corners, irregular vertices."""
    rng = np.random.default_rng(3)
    V = np.array([[0, 0], [1, 0], [2, 0], [3, 0], [0, 1], [1, 1], [2, 1.2], [3, 1],
                  [0, 2], [1, 2], [2.5, 2.2], [1.5, 3]], float)
    V = np.c_[V, 0.3 * rng.standard_normal(len(V))]
    F = [[0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [4, 5, 9, 8], [5, 6, 10, 11, 9], [6, 7, 10]]
    return Mesh(V, F, name="mixed")


def reference_catmull_clark(mesh: Mesh) -> np.ndarray:
    """Loop-per-face Catmull-Clark with boundary/corner rules: ``(n + e + m, 3)`` positions
    in the order of :func:`catmull_clark` (vertex, edge, face points)."""
    V, t = mesh.V, mesh.topology
    faces = mesh.faces_list()
    fp = np.array([V[f].mean(axis=0) for f in faces])
    edge_id = {tuple(e): i for i, e in enumerate(t.edges.tolist())}
    ef = {i: [] for i in range(len(t.edges))}
    for fi, f in enumerate(faces):
        for a, b in zip(f, f[1:] + f[:1]):
            ef[edge_id[(min(a, b), max(a, b))]].append(fi)
    ep = []
    for i, (a, b) in enumerate(t.edges.tolist()):
        if len(ef[i]) == 1:
            ep.append(0.5 * (V[a] + V[b]))
        else:
            ep.append(0.25 * (V[a] + V[b] + fp[ef[i][0]] + fp[ef[i][1]]))
    vp = []
    for v in range(len(V)):
        inc = [i for i, e in enumerate(t.edges.tolist()) if v in e]
        nbr = [t.edges[i][0] + t.edges[i][1] - v for i in inc]
        bnd = [t.edges[i][0] + t.edges[i][1] - v for i in inc if len(ef[i]) == 1]
        fs = [fi for fi, f in enumerate(faces) if v in f]
        if bnd and len(fs) == 1:
            vp.append(V[v])
        elif bnd:
            vp.append(0.75 * V[v] + 0.125 * (V[bnd[0]] + V[bnd[1]]))
        else:
            k = len(fs)
            Q = fp[fs].mean(axis=0)
            R = np.mean([0.5 * (V[v] + V[w]) for w in nbr], axis=0)
            vp.append((Q + 2 * R + (k - 3) * V[v]) / k)
    return np.concatenate([np.array(vp), np.array(ep), fp])


def test_cube_one_step_matches_hand_formula():
    fine, S = catmull_clark(cube())
    n, e = 8, 12
    # vertex (1,1,1): Q = (1/3,1/3,1/3), R = (2/3,2/3,2/3), (Q + 2R) / 3 = 5/9
    assert np.allclose(np.abs(fine.V[:n]), 5 / 9, atol=1e-15)
    # edge (1,1,1)-(1,1,-1): ((1,1,1) + (1,1,-1) + (1,0,0) + (0,1,0)) / 4 = (3/4, 3/4, 0)
    ep = np.sort(np.abs(fine.V[n:n + e]), axis=1)
    assert np.allclose(ep, [0, 0.75, 0.75], atol=1e-15)
    assert np.allclose(np.sort(np.abs(fine.V[n + e:]), axis=1), [0, 0, 1], atol=1e-15)
    assert fine.n_faces == 24 and fine.is_quad and fine.notes == []
    assert np.allclose(S.sum(axis=1), 1.0)


def test_catmull_clark_matches_loop_reference_with_boundary():
    m = mixed()
    fine, S = catmull_clark(m)
    assert np.allclose(fine.V, reference_catmull_clark(m), atol=1e-14)
    assert np.allclose(S @ m.V, fine.V)
    assert fine.is_quad and fine.n_faces == int(m.face_sizes.sum())
    assert fine.notes == []  # orientation carried over, nothing flipped


@pytest.mark.parametrize("scheme", ["catmull_clark", "doo_sabin"])
def test_rows_sum_to_one_and_rigid_motion_commutes(scheme, rotation):
    for m in (cube(), mixed(), shapes.grid(5, 4)):
        fine, S = SCHEMES[scheme](m, 2)
        assert np.allclose(np.asarray(S.sum(axis=1)).ravel(), 1.0, atol=1e-14)
        assert S.min() >= 0.0
        R, t = rotation(5), np.array([3.0, -2.0, 7.0])
        moved, _ = SCHEMES[scheme](m.with_vertices(2.5 * m.V @ R.T + t), 2)
        assert np.allclose(moved.V, 2.5 * fine.V @ R.T + t, atol=1e-12)


@pytest.mark.parametrize("scheme", ["catmull_clark", "doo_sabin"])
def test_plane_stays_planar(scheme, rotation):
    rng = np.random.default_rng(1)
    m = mixed()
    V = np.c_[m.V[:, :2] + 0.1 * rng.standard_normal((m.n_vertices, 2)), np.zeros(m.n_vertices)]
    R = rotation(2)
    fine, _ = subdivide(m.with_vertices(V @ R.T + [1.0, 2.0, 3.0]), scheme, 3)
    height = (fine.V - [1.0, 2.0, 3.0]) @ R[:, 2]  # component along the rotated z axis
    assert np.abs(height).max() < 1e-12


def _loop_from(mesh: Mesh, start: int) -> np.ndarray:
    (loop,) = mesh.topology.boundary_loops
    return np.roll(loop, -int(np.nonzero(loop == start)[0][0]))


@pytest.mark.parametrize("scheme, degree", [("catmull_clark", 3), ("doo_sabin", 2)])
def test_boundary_follows_the_curve_rule_and_corners_stay(scheme, degree):
    rng = np.random.default_rng(4)
    g = shapes.grid(5, 4, size=(4.0, 3.0))
    m = g.with_vertices(g.V + 0.2 * rng.standard_normal(g.V.shape))
    fine, _ = SCHEMES[scheme](m)
    corner_ids = np.nonzero(m.topology.star_size == 1)[0]
    coarse = _loop_from(m, 0)
    cut = np.nonzero(np.isin(coarse, corner_ids))[0]
    expected = []
    for a, b in zip(cut, list(cut[1:]) + [len(coarse)]):
        side = m.V[np.r_[coarse[a:b], coarse[b % len(coarse)]]]
        expected.append(lane_riesenfeld(side, False, degree)[0][:-1])  # end = next side's start
    expected = np.concatenate(expected)
    # the fine loop starts at the fine copy of corner 0 (CC keeps its index; DS appends it)
    start = 0 if scheme == "catmull_clark" else int(np.nonzero(np.all(fine.V == m.V[0], axis=1))[0][0])
    got = fine.V[_loop_from(fine, start)]
    assert got.shape == expected.shape
    assert np.allclose(got, expected, atol=1e-14)
    for c in corner_ids:
        assert np.any(np.all(fine.V == m.V[c], axis=1))


def test_crease_follows_the_cubic_rule():
    rng = np.random.default_rng(6)
    g = shapes.grid(5, 5)
    m = g.with_vertices(g.V + [0, 0, 1] * rng.standard_normal((25, 1)) * 0.3)
    line = np.arange(5) * 5 + 2  # the column j = 2, boundary to boundary
    fine, S = catmull_clark(m, creases=np.stack([line[:-1], line[1:]], axis=1))
    e = {tuple(x): i for i, x in enumerate(m.topology.edges.tolist())}
    fine_line = [line[0]]
    for a, b in zip(line[:-1], line[1:]):
        fine_line += [25 + e[(min(a, b), max(a, b))], b]
    expected, _ = lane_riesenfeld(m.V[line], False, 3)
    assert np.allclose(fine.V[fine_line], expected, atol=1e-14)
    smooth, _ = catmull_clark(m)
    assert not np.allclose(smooth.V[fine_line], expected, atol=1e-3)


def test_user_corners_stay_through_levels():
    m = mixed()
    fine, _ = catmull_clark(m, 3, corners=[5])
    assert np.array_equal(fine.V[5], m.V[5])


def test_levels_compose():
    m = mixed()
    f2, S2 = catmull_clark(m, 2)
    f1, S1 = catmull_clark(m)
    g, T = catmull_clark(f1)
    assert np.allclose(f2.V, g.V) and np.array_equal(f2.F, g.F)
    assert abs(S2 - T @ S1).max() < 1e-15
    f0, S0 = doo_sabin(m, 0)
    assert f0 is m and S0.shape == (m.n_vertices, m.n_vertices)


def test_doo_sabin_counts_on_the_cube_and_grid():
    fine, _ = doo_sabin(cube())
    assert fine.n_vertices == 24 and np.bincount(fine.face_sizes).tolist()[3:] == [8, 18]
    assert fine.notes == [] and fine.topology.boundary_loops == []
    grid, _ = doo_sabin(shapes.grid(4, 3), 2)
    assert grid.is_quad and len(grid.topology.boundary_loops) == 1 and grid.notes == []
    # Euler characteristic kept
    for m in (cube(), mixed()):
        f, _ = doo_sabin(m)
        chi = lambda x: x.n_vertices - len(x.topology.edges) + x.n_faces  # noqa: E731
        assert chi(f) == chi(m)


def test_doo_sabin_weights_for_a_regular_quad():
    q = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2, 3]])
    fine, S = doo_sabin(q)
    # the corner point of vertex 0: 9/16 v0 + 3/16 (v1 + v3) + 1/16 v2
    assert np.allclose(S[0].toarray().ravel(), [9 / 16, 3 / 16, 1 / 16, 3 / 16])


def test_bad_arguments_raise():
    with pytest.raises(ConfigError):
        catmull_clark(cube(), -1)
    with pytest.raises(ConfigError):
        subdivide(cube(), "loop")
    with pytest.raises(MeshError, match="not an edge"):
        catmull_clark(cube(), creases=[[0, 7]])


# -- curves ----------------------------------------------------------------------------

def test_chaikin_is_degree_two_and_cuts_corners():
    P = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    Q, S = chaikin(P, closed=True)
    assert np.allclose(Q[:2], [[0.25, 0], [0.75, 0]])
    assert np.allclose(Q, lane_riesenfeld(P, True, 2)[0])
    Qo, _ = chaikin(P, closed=False)
    assert np.allclose(Qo[[0, -1]], P[[0, -1]]) and len(Qo) == 8


@pytest.mark.parametrize("closed", [True, False])
@pytest.mark.parametrize("degree", [1, 2, 3])
def test_curve_operators_are_affine(closed, degree):
    S = curve_operator(7, closed, degree)
    assert np.allclose(np.asarray(S.sum(axis=1)).ravel(), 1.0)


def test_cubic_converges_to_the_b_spline_limit():
    rng = np.random.default_rng(0)
    P = rng.standard_normal((6, 3))
    Q, _ = lane_riesenfeld(P, True, 3, levels=12)
    limit = (np.roll(P, 1, axis=0) + 4 * P + np.roll(P, -1, axis=0)) / 6
    assert np.allclose(Q[:: 2 ** 12], limit, atol=1e-6)
    # cubic masks: (1, 6, 1) / 8 and (1, 1) / 2
    Q1, _ = lane_riesenfeld(P, True, 3)
    assert np.allclose(Q1[2], (P[0] + 6 * P[1] + P[2]) / 8) and np.allclose(Q1[3], (P[1] + P[2]) / 2)


def test_open_high_degree_is_refused():
    with pytest.raises(ConfigError):
        curve_operator(5, False, 4)
    with pytest.raises(ConfigError):
        curve_operator(2, True, 3)
