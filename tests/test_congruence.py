"""Congruence classes (issue 37 item 1): how many different glass shapes, node types and beam types."""
import numpy as np
from fabricate.cad.congruence import glass_classes, mirror_rings, ring_classes, vector_classes

Q = np.array([[0.0, 0.0], [1500.0, 0.0], [1400.0, 900.0], [100.0, 1000.0]])  # no symmetry
ROT = np.array([[0.6, -0.8], [0.8, 0.6]])


def test_moved_relabelled_and_mirrored_quads():
    moved = np.roll(Q, 1, axis=0) @ ROT.T + 300.0                                # rigid motion, corners relabelled
    mirror = mirror_rings(Q) @ ROT.T - 50.0                                      # the other hand (still ccw)
    inside = Q + [[0, 0], [0.9, 0], [0, 0], [0, 0]]                              # one corner 0.9 mm out
    outside = Q + [[0, 0], [2.5, 0], [0, 0], [0, 0]]                             # 2.5 mm out: the fit leaves > 1 mm
    c = ring_classes(np.stack([Q, moved, mirror, inside, outside])[:, None], tol=1.0)
    assert c.label.tolist() == [0, 0, 0, 0, 1] and c.hand.tolist() == [0, 0, 1, 0, 0]
    assert c.count == 2 and c.positions == 3 and c.names("G") == ["G001A", "G001A", "G001B", "G001A", "G002"]
    assert c.shift[1] == 1                                                       # corner 0 of Q is corner 1 of moved
    assert c.deviation[1] < 1e-9 and 0.4 < c.deviation[3] <= 1.0
    assert ring_classes(np.stack([Q, inside])[:, None], tol=0.3).count == 2      # just outside a finer tolerance


def test_a_symmetric_shape_has_one_hand():
    trapezoid = np.array([[0.0, 0.0], [2000.0, 0.0], [1600.0, 1000.0], [400.0, 1000.0]])
    c = ring_classes(np.stack([trapezoid, mirror_rings(trapezoid) + 7.0])[:, None])
    assert c.count == 1 and c.positions == 1 and c.hand.tolist() == [0, 0] and c.names("G") == ["G001"] * 2


def test_rings_move_together_and_per_corner_values_must_agree():
    """Two plies of a unit: each alone congruent, but not laid the same way on each other."""
    inner = Q * 0.98 + 10.0
    unit = np.stack([Q, inner])
    shifted = np.stack([Q, inner + [3.0, 0.0]])
    assert ring_classes(np.stack([unit, shifted])).count == 2
    assert ring_classes(np.stack([unit, unit @ ROT.T])).count == 1
    F = np.zeros((2, 1, 4, 1))
    F[1, 0, 2, 0] = 1.5                                                          # a node: one beam 1.5 mm higher
    assert ring_classes(np.stack([Q, Q])[:, None], F=F).count == 2


def test_without_translation_only_rotations_about_the_origin():
    assert ring_classes(np.stack([Q, Q @ ROT.T])[:, None], translate=False).count == 1
    assert ring_classes(np.stack([Q, Q + 5.0])[:, None], translate=False).count == 2


def test_leaders_do_not_chain():
    """0.6 mm steps: each within 1 mm of the next, the ends 1.8 mm apart: not one class."""
    steps = np.stack([Q + [[0, 0], [0.6 * i, 0], [0, 0], [0, 0]] for i in range(4)])[:, None]
    c = ring_classes(steps, tol=1.0)
    assert c.count == 2 and (c.deviation <= 1.0).all()


def test_vector_classes_spellings_and_hands():
    made = np.array([1000.0, 1.0, 2.0])
    D = np.stack([
        [made, made[[0, 2, 1]], made * [1, -1, -1], made[[0, 2, 1]] * [1, -1, -1]],   # spellings of one part
        [made[[0, 2, 1]], made, made[[0, 2, 1]] * [1, -1, -1], made * [1, -1, -1]],   # it, the other end first
        [made * [1, -1, -1], made[[0, 2, 1]] * [1, -1, -1], made, made[[0, 2, 1]]],   # its mirror image
        [made + [1.5, 0, 0]] * 4])                                                 # 1.5 mm longer
    c = vector_classes(D, tol=1.0, spellings=2)
    assert c.label.tolist() == [0, 0, 0, 1] and c.hand.tolist() == [0, 0, 1, 0]


def test_a_dome_has_one_type_per_ring_by_construction():
    """A surface of revolution with n-fold symmetry and mirror planes: glass shapes = rings of faces,
    node types = rings of vertices, beam types = rings of edges (orbits of the symmetry group);
    invariant under a rigid motion of the whole roof."""
    from cad_fixtures import dome_structure, rigid

    from fabricate.cad import PartSpec, build_parts
    from fabricate.export.schedules import beam_types, node_types
    from fabricate.offset import offset_structure

    s = dome_structure(n_around=8, k=4)
    for structure in (s, offset_structure(s.mesh.with_vertices(rigid(s.mesh.V)), (0.0, -200.0))):
        parts = build_parts(structure, PartSpec(glass={"type": "laminated", "plies_mm": [8, 8]}))
        ids, c = glass_classes(parts)
        assert len(ids) == 32 - 8 and c.count == 3 and c.positions == 3 and c.largest == 8
        assert node_types(parts)[2].count == 4
        assert beam_types(parts)[2].count == 7 and beam_types(parts)[2].positions == 7


def test_a_roof_with_leaning_joints_has_mirror_hands():
    """A row of four panels whose joints lean out on the left half and in on the right half: panels 1
    and 4 are mirror images, and 2 and 3 (two shapes, two hands each: a glass order's four positions)."""
    from optimize.mesh import Mesh

    from fabricate.cad import PartSpec, build_parts
    from fabricate.offset import offset_structure

    top = np.array([0.0, 1350.0, 2400.0, 3450.0, 4800.0])                        # joints at 1200, 2400, 3600 below
    V = np.array([[1200.0 * i, 0.0, 0.0] for i in range(5)] + [[x, 1500.0, 0.0] for x in top])
    F = [[i, i + 1, i + 6, i + 5] for i in range(4)]
    parts = build_parts(offset_structure(Mesh(V, F), (0.0, -200.0)), PartSpec())
    ids, c = glass_classes(parts)
    assert ids == ["P0001", "P0002", "P0003", "P0004"]
    assert c.label.tolist() == [0, 1, 1, 0] and c.hand.tolist() == [0, 0, 1, 1]
    assert c.count == 2 and c.positions == 4 and float(c.deviation.max()) < 1e-6
