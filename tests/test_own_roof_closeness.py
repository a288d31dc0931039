"""A user's own roof, closer to its design (#30 item 2): the closeness continuation after the
constrained fairing phase (``optimize.solvers.fairing.closer``)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from optimize.api import optimize_mesh
from optimize.mesh import measures
from optimize.mesh.io.api import read_mesh
from optimize.solvers import fairing, guided
from optimize.terms.fairness import roughness
from optimize.tolerances import Tolerances

ROOF = Path(__file__).resolve().parents[1] / "configs" / "meshes" / "compas_quadmesh.obj"


@pytest.fixture(scope="module")
def roof():
    """The shipped 5 x 5 m freeform quad roof (COMPAS, MIT), in mm."""
    m = read_mesh(ROOF)
    return m.with_vertices(m.V * 1000.0)


@pytest.fixture(scope="module")
def conical(roof):
    return optimize_mesh(roof, "conical")


def test_far_result_moves_closer_and_stays_fair_and_exact(roof, conical):
    """Own lines, conical: the fairing phase alone leaves the roof beyond the closeness tolerance;
    the continuation takes it closer, no rougher than the tolerance allows, conical and fold-free."""
    tol = Tolerances()
    rec = conical.defects["closer"]
    assert rec["start"] > tol.closeness
    assert any(r["kept"] for r in rec["rounds"])
    assert rec["end"] < rec["start"]
    assert conical.defects["distance"]["max_relative"] == pytest.approx(rec["end"], rel=1e-6)
    assert conical.success
    assert measures.conical_defect(conical.mesh).max() <= tol.conical
    assert measures.planarity(conical.mesh).max() <= tol.planarity
    assert roughness(conical.mesh) <= tol.roughness * roughness(roof)
    assert not measures.folded_faces(roof, conical.mesh.V, roof.V, tol.fold).any()
    # no edge pulled onto its neighbour: every edge keeps most of the floor of the continuation
    E = roof.topology.edges
    ratio = (np.linalg.norm(conical.mesh.V[E[:, 0]] - conical.mesh.V[E[:, 1]], axis=1)
             / np.linalg.norm(roof.V[E[:, 0]] - roof.V[E[:, 1]], axis=1))
    assert ratio.min() >= 0.9 * fairing.SHORTEST


def test_every_round_kept_obeys_the_roughness_limit(conical):
    for r in conical.defects["closer"]["rounds"]:
        if r["kept"]:
            assert r["roughness_ratio"] <= Tolerances().roughness


def test_a_result_within_tolerance_is_left_alone():
    """No continuation when the iterate is close already (the default path is not slowed)."""
    from optimize.proximity.surface import Reference
    from optimize.terms.formulation import Formulation
    from optimize.terms.problem import describe

    u, v = np.meshgrid(np.linspace(-1, 1, 5), np.linspace(-1, 1, 5))
    V = np.stack([u.ravel(), v.ravel(), 0.1 * (u ** 2 + v ** 2).ravel()], 1)
    idx = np.arange(25).reshape(5, 5)
    F = np.stack([idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()], 1)
    from optimize.mesh import Mesh

    mesh = Mesh(V, F)
    spec = describe(mesh, "conical", "default", formulation="auto", beams=False, fixed=None, glide_boundary=False,
                    convex=False, fairness=1e-3, closeness=1e-2, reference=None)
    form = Formulation(mesh, "conical", spec=spec)
    x = form.start(mesh.V)
    run = guided.RunState(x=x, status="converged", message="m", nit=3)
    out, rec = fairing.closer(form, run, x, ref=Reference(mesh), glide=None, convex=None, tol=Tolerances(),
                              fairness=1e-3, closeness=1e-2)
    assert out is run and rec["rounds"] == [] and rec["start"] == 0.0
