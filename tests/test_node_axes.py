"""Node axes exist once (``optimize.mesh.axes``): the optimizer's result axes (default and
paper methods), the auxiliary formulation's starting axes and the offset stage's fit agree on a
mesh that is conical by construction, and match the circle axis of the four normals computed
here independently (perpendicular to ``n0 - n2`` and ``n1 - n3``)."""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from fabricate.offset import face_planes, fit_axes
from optimize.api import optimize_mesh
from optimize.mesh import Mesh
from optimize.mesh.measures import conical_defect
from optimize.modelling import shapes
from optimize.solvers.paper.problem import node_axes
from optimize.terms import conical
from optimize.terms.formulation import Formulation


def _conical_mesh() -> Mesh:
    """An open surface of revolution (conical: its face planes around a vertex touch one cone),
    turned and moved so no axis is a coordinate axis."""
    m = shapes.revolution(shapes.dome_profile(radius=8.0, rise=3.0, k=7), 12, sweep=1.5 * np.pi)
    R = Rotation.from_rotvec([0.3, -0.7, 0.5]).as_matrix()
    return Mesh(m.V @ R.T + [1.0, -2.0, 0.5], m.F, name="turned_dome")


def _circle_axes(mesh: Mesh, normals: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Reference: the axis of the circle through the four normals at each vertex of ``p``, one
    vertex at a time."""
    out = []
    for v in p:
        n = normals[mesh.topology.star_faces[v, :4]]
        a = np.cross(n[0] - n[2], n[1] - n[3])
        a /= np.linalg.norm(a)
        out.append(a if a @ n.sum(axis=0) > 0 else -a)
    return np.array(out)


def test_the_former_axis_fits_agree_on_a_conical_mesh():
    mesh = _conical_mesh()
    assert conical_defect(mesh).max() < 1e-12
    p = mesh.topology.interior_valence4
    assert len(p) > 10
    normals = face_planes(mesh)[0]
    reference = _circle_axes(mesh, normals, p)
    offset = fit_axes(mesh, normals)
    paper_axes, paper_angles = node_axes(mesh)
    default = optimize_mesh(mesh, "conical")
    auxiliary = optimize_mesh(mesh, "conical", formulation="auxiliary")
    form = Formulation(mesh, "conical", "auxiliary")
    start = form.layout.view(form.start(mesh.V), "axes")
    cone = conical.cone_faces(mesh)  # the rows of ``start``: (p, 4) faces of the cone vertices
    np.testing.assert_array_equal(cone, mesh.topology.star_faces[form.cone_vertices, :4])
    for axes in (offset.axes[p], paper_axes[p], default.axes[p], auxiliary.axes[p]):
        np.testing.assert_allclose(axes, reference, atol=1e-9)
    order = np.searchsorted(p, form.cone_vertices)
    np.testing.assert_allclose(start, reference[order], atol=1e-9)
    # every face at a vertex makes the cone angle with its axis
    cosines = np.einsum("psj,pj->ps", normals[mesh.topology.star_faces[p, :4]], reference)
    for angles in (np.arccos(offset.cos_theta[p]), paper_angles[p], default.cone_angles[p],
                   auxiliary.cone_angles[p]):
        np.testing.assert_allclose(np.broadcast_to(np.cos(angles)[:, None], cosines.shape), cosines, atol=1e-9)
    # off the valence-4 interior, the optimizer reports the offset stage's axes
    rest = np.setdiff1d(np.arange(mesh.n_vertices), p)
    for axes in (paper_axes, default.axes):
        np.testing.assert_allclose(axes[rest], offset.axes[rest], atol=1e-9)
