"""Topology: valence, boundary, stars in cyclic order, polylines, loops, orientation, components."""
import numpy as np
import pytest

from optimize import Mesh


def _moebius(n=12, width=0.3):
    """A Moebius band: n quads around a circle, the strip turned half a turn."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    s = np.array([-width, width])
    r = 1 + s[None, :] * np.cos(t / 2)[:, None]
    V = np.stack([r * np.cos(t)[:, None], r * np.sin(t)[:, None],
                  s[None, :] * np.sin(t / 2)[:, None]], axis=2).reshape(-1, 3)
    F = [[2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1] for i in range(n - 1)]
    F.append([2 * (n - 1), 1, 0, 2 * (n - 1) + 1])  # the half turn: sides swap
    return Mesh(V, F, name="moebius")


def _cube():
    V = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    F = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    return Mesh(V, F, name="cube")


def _pentagon_star():
    """Five quads around vertex 0: an interior vertex of valence 5."""
    a = np.linspace(0, 2 * np.pi, 5, endpoint=False)
    mid = np.stack([np.cos(a), np.sin(a), np.zeros(5)], axis=1)
    far = np.stack([1.6 * np.cos(a + np.pi / 5), 1.6 * np.sin(a + np.pi / 5), np.zeros(5)], axis=1)
    V = np.vstack([[[0, 0, 0]], mid, far])
    F = [[0, 1 + i, 6 + i, 1 + (i + 1) % 5] for i in range(5)]
    return Mesh(V, F, name="star5")


# -- a 3 x 3 quad grid (4 x 4 vertices) -----------------------------------------------
def test_grid_valence_and_boundary(grid3x3):
    t = grid3x3.topology
    ij = np.array([(i, j) for i in range(4) for j in range(4)])
    border = (ij == 0) | (ij == 3)
    corner = border.all(axis=1)
    side = border.any(axis=1) & ~corner
    assert np.array_equal(t.is_boundary_vertex, border.any(axis=1))
    assert np.all(t.valence[corner] == 2) and np.all(t.valence[side] == 3)
    assert np.all(t.valence[~border.any(axis=1)] == 4)
    assert np.array_equal(t.star_size, np.where(corner, 1, np.where(side, 2, 4)))
    assert len(t.edges) == 24 and int(t.is_boundary_edge.sum()) == 12
    assert sorted(t.interior_valence4.tolist()) == [5, 6, 9, 10]


def test_grid_boundary_loop_is_a_closed_walk(grid3x3):
    t = grid3x3.topology
    (loop,) = t.boundary_loops
    assert sorted(loop.tolist()) == sorted(np.nonzero(t.is_boundary_vertex)[0].tolist())
    edges = {tuple(e) for e in t.edges[t.is_boundary_edge].tolist()}
    for a, b in zip(loop, np.roll(loop, -1)):
        assert (min(a, b), max(a, b)) in edges


def test_twins_and_edge_faces(grid3x3):
    t = grid3x3.topology
    inner = t.twin >= 0
    assert np.array_equal(t.twin[t.twin[inner]], np.nonzero(inner)[0])
    # twin half-edges run the opposite way (consistent orientation)
    assert np.array_equal(t.corner_vertex[t.twin[inner]], t.corner_next_vertex[inner])
    assert np.all((t.edge_faces[:, 1] >= 0) == ~t.is_boundary_edge)


def test_stars_are_counter_clockwise(grid3x3):
    """Neighbours of an interior vertex turn counter-clockwise about +z (faces are CCW)."""
    t, V = grid3x3.topology, grid3x3.V
    for v in t.interior_valence4:  # a loop in a test, as the reference
        d = V[t.star_neighbors[v, :4]] - V[v]
        ang = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
        assert np.allclose(np.diff(ang), np.pi / 2)
        faces = t.star_faces[v, :4]
        for f, g in zip(faces, np.roll(faces, -1)):  # consecutive faces share an edge
            assert len(set(grid3x3.F[f]) & set(grid3x3.F[g])) == 2


def test_boundary_star_starts_at_the_boundary(grid3x3):
    t = grid3x3.topology
    v = 1  # (0, 1): a side vertex with two faces and three neighbours
    nb = t.star_neighbors[v, :3]
    assert t.is_boundary_vertex[nb[0]] and t.is_boundary_vertex[nb[2]]
    assert not t.is_boundary_vertex[nb[1]]


def test_grid_polylines_are_rows_and_columns(grid3x3):
    t, V = grid3x3.topology, grid3x3.V
    lines = t.polylines
    assert len(lines) == 8 and all(len(p) == 4 for p in lines)
    used = [tuple(sorted(e)) for p in lines for e in zip(p[:-1], p[1:])]
    assert sorted(used) == sorted(map(tuple, t.edges.tolist()))  # every edge exactly once
    for p in lines:  # straight: all points on one coordinate line
        assert np.ptp(V[p, 0]) == 0 or np.ptp(V[p, 1]) == 0
    assert len(t.fair_triples) == 2 * 4 + 8


def test_revolution_polylines_close_around_the_axis(revolution):
    t = revolution.topology
    closed = [p for p in t.polylines if p[0] == p[-1]]
    open_ = [p for p in t.polylines if p[0] != p[-1]]
    assert len(closed) == 7 and all(len(p) == 17 for p in closed)  # parallels
    assert len(open_) == 16 and all(len(p) == 7 for p in open_)  # meridians
    assert len(t.boundary_loops) == 2 and t.n_components == 1


# -- orientation, components, irregular vertices ---------------------------------------
def test_inconsistent_face_is_flipped_and_noted(grid3x3):
    F = grid3x3.F.copy()
    F[4] = F[4][::-1]
    m = Mesh(grid3x3.V, F, name="flipped")
    assert np.array_equal(m.F, grid3x3.F)
    assert m.topology.flipped_faces.size == 0 and m.topology.orientable
    assert len(m.notes) == 1 and "1 face(s)" in m.notes[0] and "flipped" in m.notes[0]
    assert "[4]" in m.notes[0]


def test_moebius_band_is_not_orientable():
    m = _moebius()
    t = m.topology
    assert not t.orientable and t.flipped_faces.size == 0
    assert any("not orientable" in n for n in m.notes)
    (loop,) = t.boundary_loops  # one boundary curve, twice around
    assert len(loop) == 24
    assert np.all(t.valence == 3)


def test_two_components(grid3x3):
    other = grid3x3.V + [10.0, 0, 0]
    m = Mesh(np.vstack([grid3x3.V, other]), np.vstack([grid3x3.F, grid3x3.F + 16]))
    t = m.topology
    assert t.n_components == 2
    assert np.array_equal(t.component, np.repeat([t.component[0], t.component[16]], 16))
    assert len(t.boundary_loops) == 2 and len(t.polylines) == 16


def test_cube_has_valence_three_and_no_boundary():
    t = _cube().topology
    assert np.all(t.valence == 3) and not t.is_boundary_vertex.any()
    assert len(t.edges) == 12 and t.boundary_loops == []
    assert t.interior_valence4.size == 0 and t.fair_triples.shape == (0, 3)
    assert len(t.polylines) == 12  # no straight continuation: every edge alone


def test_valence_five_vertex():
    t = _pentagon_star().topology
    assert t.valence[0] == 5 and not t.is_boundary_vertex[0]
    assert t.interior_valence4.size == 0
    assert sorted(t.star_neighbors[0, :5].tolist()) == [1, 2, 3, 4, 5]
    assert len(t.boundary_loops[0]) == 10


@pytest.mark.parametrize("k", [3, 6])
def test_triangle_and_hexagon_fans(k):
    a = np.linspace(0, 2 * np.pi, k, endpoint=False)
    V = np.vstack([[[0, 0, 0]], np.stack([np.cos(a), np.sin(a), 0 * a], axis=1)])
    F = [[0, 1 + i, 1 + (i + 1) % k] for i in range(k)]
    t = Mesh(V, F).topology
    assert t.valence[0] == k and t.star_size[0] == k and not t.is_boundary_vertex[0]


def test_orientation_fix_flips_the_minority(grid3x3):
    F = grid3x3.F.copy()
    F[0] = F[0][::-1]  # the first face (the search root) is the odd one out
    m = Mesh(grid3x3.V, F, name="flipped0")
    assert np.array_equal(m.F, grid3x3.F)
    assert "1 face(s)" in m.notes[0] and "[0]" in m.notes[0]
