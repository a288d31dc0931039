"""The built-in design ``tunnel`` (optimize/modelling/design_tunnel.py) and the mesh shipped from it."""
import numpy as np
import pytest

from optimize import ConfigError
from optimize.mesh import measures
from optimize.modelling.design_tunnel import control_mesh, flatten
from optimize.modelling.designs import DESIGNS
from optimize.mesh.io import read_mesh

from conftest import TUNNEL


@pytest.fixture(scope="module")
def tunnel():
    return DESIGNS["tunnel"]()


def _irregular(mesh):
    t = mesh.topology
    inner = ~t.is_boundary_vertex
    return int(np.sum(inner & (t.valence == 3))), int(np.sum(inner & (t.valence == 5)))


def test_shipped_mesh_is_the_design_in_metres(tunnel):
    shipped = read_mesh(TUNNEL)  # configs/meshes/tunnel.off, read by configs/halftunnel*.yaml
    assert np.array_equal(shipped.F, tunnel.mesh.F)
    assert np.abs(shipped.V - tunnel.mesh.V / 1000.0).max() < 1e-9


def test_a_pair_of_pants_with_irregular_vertices_nearly_planar_not_conical(tunnel):
    m = tunnel.mesh
    t = m.topology
    assert m.n_faces == 784 and m.is_quad and not m.notes  # consistently oriented as built
    assert len(t.boundary_loops) == 3 and t.n_components == 1
    assert m.n_vertices - len(t.edges) + m.n_faces == -1  # Euler characteristic of a pair of pants
    assert _irregular(m) == (2, 6)
    assert measures.planarity(m).max() == pytest.approx(3e-5, rel=1e-6)
    assert measures.conical_defect(m).max() > 1.0
    assert (tunnel.target, tunnel.levels, tunnel.units) == ("conical", 0, "mm")
    # outward normals: the roof's middle face points up, the floor's down
    n = measures.face_normals(m)
    c = m.V[m.F].mean(axis=1)
    assert n[np.argmax(c[:, 2])][2] > 0.9 and n[np.argmin(c[:, 2])][2] < -0.9


def test_one_subdivision_keeps_the_irregular_vertices_and_loops():
    m = DESIGNS["tunnel"](subdivisions=1).mesh
    assert m.n_faces == 196 and _irregular(m) == (2, 6) and len(m.topology.boundary_loops) == 3


def test_junction_kites_are_circular_in_the_control_mesh():
    """The junction hexagons' quads have right angles at the triangle's side midpoints."""
    c = control_mesh(width=4000.0, height=3200.0, lengths=(10000.0, 8000.0, 8000.0), bend_deg=20.0,
                     taper=1.0, rise=0.0, rings=(4, 3, 3))
    assert c.n_faces == 49
    assert measures.circular_defect(c)[:6].max() < 1e-12 and measures.planarity(c)[:6].max() < 1e-12


def test_flatten_moves_little_and_reaches_what_is_asked(tunnel):
    from optimize.modelling.subdivision import catmull_clark

    coarse = control_mesh(width=4000.0, height=3200.0, lengths=(10000.0, 8000.0, 8000.0), bend_deg=20.0,
                          taper=1.0, rise=0.0, rings=(4, 3, 3))
    smooth = catmull_clark(coarse, 2)[0]
    assert measures.planarity(smooth).max() > 1e-2  # subdivision alone is far from planar
    planar = flatten(smooth, 0.0)
    assert measures.planarity(planar).max() < 1e-12
    assert np.abs(planar.V - smooth.V).max() < 0.02 * smooth.bbox_diagonal()
    assert np.array_equal(flatten(smooth, 3e-5).V, tunnel.mesh.V)


@pytest.mark.parametrize("kw,match", [
    ({"main_length": 2000.0}, "main_length=2000.0, expected more than"),
    ({"bend_deg": 60.0}, "bend_deg=60.0, expected -45..45"),
    ({"subdivisions": 5}, "subdivisions=5, expected an integer in 0..4"),
    ({"planarity": -1.0}, "planarity=-1.0, expected a number in"),
])
def test_bad_parameters_name_the_key(kw, match):
    with pytest.raises(ConfigError, match=match):
        DESIGNS["tunnel"](**kw)
