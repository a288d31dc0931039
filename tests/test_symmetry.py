"""The design's symmetry is kept (#37 item 2): optimize.mesh.symmetry detects the rigid symmetries of a
mesh, and optimize_mesh returns a symmetric result for a symmetric input, with congruent panels."""
import numpy as np
import pytest

from optimize.api import optimize_mesh
from optimize.mesh import symmetry
from optimize.mesh.congruence import face_classes
from optimize.modelling import shapes


def _dome(meridians=12, rings=4):
    return shapes.revolution(shapes.dome_profile(6000.0, 2500.0, rings), meridians, name="dome")


def _twisted(seed=1):
    """A dome of 12 x 3 quads, noisy but exactly symmetric under its 12 rotations (no mirror): not PQ."""
    m = _dome()
    G = symmetry.detect(m)
    rot = symmetry.Group(tuple(g for g in G.maps if np.linalg.det(g.R) > 0), G.tol)
    noisy = shapes.perturbed(m, 0.05, seed=seed)
    return noisy.with_vertices(rot.symmetrize(noisy.V))


def _canopy(seed=2):
    """A 7 x 5 quad canopy over a saddle, noisy but exactly mirror-symmetric in x = 3.5 (one mirror)."""
    g = shapes.grid(8, 6, (7.0, 5.0), height=lambda x, y: 0.3 * ((x - 3.5) ** 2 - (y - 2.0) ** 2 / 2) / 4)
    g = g.with_vertices(g.V * 1000.0, name="canopy")
    G = symmetry.detect(g)
    noisy = shapes.perturbed(g, 0.04, seed=seed)
    return noisy.with_vertices(G.symmetrize(noisy.V))


def test_detect_groups():
    G = symmetry.detect(_dome())
    assert G.order == 24 and G.kinds() == {"identity": 1, "rotation": 11, "mirror": 12}
    assert len(set(G.orbits().tolist())) == 3                       # three rings of panels
    assert symmetry.detect(_twisted()).kinds() == {"identity": 1, "rotation": 11}
    c = symmetry.detect(_canopy())
    assert c.kinds() == {"identity": 1, "mirror": 1}
    assert symmetry.detect(shapes.perturbed(_dome(), 0.01)).trivial  # noise breaks it


def test_symmetrize_is_a_projection():
    noisy = shapes.perturbed(_dome(), 0.05, seed=3)
    G = symmetry.detect(_dome())
    S = G.symmetrize(noisy.V)
    assert G.deviation(noisy.V) > 1.0 and G.deviation(S) < 1e-9
    assert np.abs(G.symmetrize(S) - S).max() < 1e-9


@pytest.mark.parametrize("make, shapes_expected", [(_twisted, 3), (_canopy, 20)])
def test_symmetric_input_symmetric_result(make, shapes_expected):
    """Counts by construction: 3 rings of 12 rotated copies; the canopy's 35 panels in 5 rows of 7,
    mirror pairs about the middle column: 5 x (3 pairs + 1 on the plane) = 20 shapes."""
    mesh = make()
    G = symmetry.detect(mesh)
    assert not G.trivial
    res = optimize_mesh(mesh, "conical")
    assert res.success
    diag = float(np.linalg.norm(np.ptp(mesh.V, axis=0)))
    assert G.deviation(res.mesh.V) <= 1e-9 * diag
    assert res.defects["symmetry"]["kept"] and res.defects["symmetry"]["order"] == G.order
    assert face_classes(res.mesh).count == shapes_expected
    assert res.defects["conical"]["max"] <= 1e-6 and res.defects["planarity"]["max"] <= 1e-6


def test_mirror_broken_by_closeness_is_restored():
    """The closeness term's footpoints (the reference fan-triangulated from each face's first corner)
    are not mirror-invariant: without the projection the canopy's result is off its mirror."""
    mesh = _canopy()
    res = optimize_mesh(mesh, "conical")
    G = symmetry.detect(mesh)
    assert res.defects["symmetry"]["deviation"] > 1e-9              # the solve alone broke it
    assert G.deviation(res.mesh.V) <= 1e-9 * float(np.linalg.norm(np.ptp(mesh.V, axis=0)))
