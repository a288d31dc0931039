"""Mesh construction: every bad input raises MeshError naming the facts; derived data."""
import numpy as np
import pytest

from optimize import Mesh, MeshError
from optimize.modelling import shapes
from optimize.mesh.measures import face_areas

SQUARE = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]


def _raises(V, F, *facts, name="bad"):
    with pytest.raises(MeshError) as err:
        Mesh(V, F, name=name)
    msg = str(err.value)
    assert msg.startswith(f"{name}: "), msg
    for fact in facts:
        assert fact in msg, (fact, msg)
    return msg


# -- one test per bad input ---------------------------------------------------------
def test_nan_coordinate():
    V = np.array(SQUARE, float)
    V[2, 1] = np.nan
    _raises(V, [[0, 1, 2, 3]], "vertex 2", "nan", "finite")


def test_inf_coordinate():
    V = np.array(SQUARE, float)
    V[3, 0] = -np.inf
    _raises(V, [[0, 1, 2, 3]], "vertex 3", "-inf", "finite")


def test_face_index_out_of_range():
    _raises(SQUARE, [[0, 1, 2, 4]], "face 0", "vertex 4", "0..3")


def test_negative_face_index():
    _raises(SQUARE, [[0, 1, 2, -3]], "face 0", "-3", "0..3")


def test_padding_before_an_index():
    _raises(SQUARE, [[0, 1, -1, 2]], "face 0", "-1 before")


def test_face_with_two_vertices():
    _raises(SQUARE, [[0, 1, 2, 3], [2, 3, -1, -1]], "face 1", "2 vertices", "at least 3")


def test_repeated_vertex_in_face():
    _raises(SQUARE, [[0, 1, 2, 1]], "face 0", "repeats", "[0, 1, 2, 1]")


def test_zero_length_edge():
    V = np.array(SQUARE + [[1, 1, 0]], float)  # vertex 4 sits on vertex 2
    _raises(V, [[0, 1, 4, 3], [1, 2, 4, -1]], "face 1", "zero-length edge 2-4")


def test_non_manifold_edge():
    V = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]]
    msg = _raises(V, [[0, 1, 2], [1, 0, 3], [0, 1, 4]], "non-manifold edge [0, 1]", "3 faces")
    assert "[0, 1, 2]" in msg  # the faces are listed


def test_non_manifold_vertex():
    # two triangles touching at vertex 0 only (a bow tie)
    V = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [-1, 0, 0], [-1, -1, 0]]
    _raises(V, [[0, 1, 2], [0, 3, 4]], "non-manifold vertex 0", "more than one fan")


def test_unused_vertex():
    _raises(SQUARE + [[5, 5, 5]], [[0, 1, 2, 3]], "vertex 4", "no face")


def test_empty_mesh():
    _raises(np.zeros((0, 3)), np.zeros((0, 4), int), "empty mesh", "0 vertices")


def test_vertices_of_wrong_shape():
    _raises(np.zeros((4, 2)), [[0, 1, 2, 3]], "(4, 2)", "(n, 3)")


def test_with_vertices_wrong_shape(quad):
    with pytest.raises(MeshError, match=r"shape \(3, 3\).*expected \(4, 3\)"):
        quad.with_vertices(np.zeros((3, 3)))


def test_with_vertices_not_finite(quad):
    V = quad.V.copy()
    V[1, 2] = np.nan
    with pytest.raises(MeshError, match="vertex 1 is not finite"):
        quad.with_vertices(V)


# -- what a valid mesh offers ---------------------------------------------------------
def test_arrays_are_read_only(quad):
    with pytest.raises(ValueError):
        quad.V[0, 0] = 5.0
    with pytest.raises(ValueError):
        quad.F[0, 0] = 1


def test_input_arrays_not_mutated():
    V = np.array(SQUARE, float) + 0.25
    F = np.array([[3, 2, 1, 0]])
    V0, F0 = V.copy(), F.copy()
    m = Mesh(V, F)
    assert np.array_equal(V, V0) and np.array_equal(F, F0)
    assert V.flags.writeable and F.flags.writeable
    m2 = m.with_vertices(m.V * 2)
    assert np.array_equal(m.V, V0) and m2.topology is m.topology


def test_ragged_faces_are_padded():
    V = SQUARE + [[2, 0.5, 0]]
    m = Mesh(V, [[0, 1, 2, 3], [1, 4, 2]])
    assert m.F.tolist() == [[0, 1, 2, 3], [1, 4, 2, -1]]
    assert m.face_sizes.tolist() == [4, 3]
    assert m.faces_list() == [[0, 1, 2, 3], [1, 4, 2]]
    assert not m.is_quad


def test_triangulate_covers_every_face(cylinder_path):
    from optimize.mesh.io import read_mesh

    m = read_mesh(cylinder_path)
    T = m.triangulate()
    assert len(T) == int((m.face_sizes - 2).sum())
    # planar convex faces: fan triangle areas add up to the face areas
    tri = Mesh(m.V, T, check=False)
    t_area = 0.5 * np.linalg.norm(np.cross(m.V[T[:, 1]] - m.V[T[:, 0]], m.V[T[:, 2]] - m.V[T[:, 0]]),
                                  axis=1)
    assert t_area.sum() == pytest.approx(face_areas(m).sum(), rel=1e-12)
    assert tri.n_faces == len(T)


def test_bbox_diagonal_and_repr(grid3x3):
    assert grid3x3.bbox_diagonal() == pytest.approx(np.sqrt(18.0))
    assert "16 vertices" in repr(grid3x3) and "9 4-gons" in repr(grid3x3)
    assert grid3x3.is_quad


def test_shapes_are_valid_meshes():
    m = shapes.translational(np.array([[0, 0, 0], [1, 0, 0.2], [2, 0, 0.1]]),
                             np.array([[0, 0, 0], [0, 1, 0.3], [0, 2, 0.0], [0, 3, 0.5]]))
    assert (m.n_vertices, m.n_faces) == (12, 6)
