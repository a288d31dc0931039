"""optimize.mesh.components: connected components in NumPy, checked against SciPy's csgraph."""
import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from optimize.mesh.components import component_labels


@pytest.mark.parametrize("n,e,seed", [(1, 0, 0), (50, 0, 1), (1000, 600, 2), (5000, 4990, 3), (3000, 9000, 4)])
def test_same_labels_as_scipy(n, e, seed):
    E = np.random.default_rng(seed).integers(0, n, (e, 2))
    A = sp.coo_matrix((np.ones(e), (E[:, 0], E[:, 1])), shape=(n, n))
    np.testing.assert_array_equal(component_labels(n, E), connected_components(A, directed=False)[1])


def test_a_long_path_backwards_is_one_component():
    n = 20000
    E = np.stack([np.arange(n - 1), np.arange(1, n)], axis=1)[::-1]
    assert (component_labels(n, E) == 0).all()


def test_two_meshes_side_by_side(grid3x3, quad):
    from optimize.modelling.strips import join_meshes

    t = join_meshes([grid3x3, quad]).topology
    assert t.n_components == 2 and np.bincount(t.component).tolist() == [16, 4]
