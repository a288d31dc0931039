"""Shared fixtures: tiny hand-made meshes and two meshes the repository makes itself.

- ``quad``: one planar unit square (counter-clockwise seen from +z).
- ``grid3x3``: 3 x 3 planar quads on 4 x 4 vertices (4 interior valence-4 vertices).
- ``revolution``: a dome of revolution, meridians x parallels: planar, conical and
  circular by construction; ``perturbed_revolution``: the same with seeded noise.
- ``tunnel_path``: ``configs/meshes/tunnel.off``, the built-in design ``tunnel`` in
  metres (784 quads, three boundary loops, 2 interior vertices of valence 3 and 6 of
  valence 5, planarity 3e-5, far from conical), shipped for the example configs;
  ``small_tunnel``: the same design after one Catmull-Clark round instead of two
  (196 quads, the same irregular vertices and loops), in metres, for the slower tests.
- ``cylinder_path``: ``shapes.capped_cylinder()`` written as OBJ (220 vertices, 200 quads
  and two 20-gon caps, exactly planar and conical).
- ``rotation``: ``rotation(seed)`` gives a seeded (3, 3) rotation matrix.

Under pytest-xdist (``--dist loadgroup``, pyproject.toml) the tests of one file run in one worker, in
file order, so a module-scoped fixture is made once (:func:`pytest_collection_modifyitems`); the tests
that read the quickstart run (``finished_run``, made once per worker) share a worker too.

Every test, whatever ran before it in the process: ifcopenshell's process-wide feature switch is
as a test found it when it ends (:func:`_ifcopenshell_as_found`), or that test fails.

Nothing here reads outside the repository.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np
import pytest

from optimize import Mesh
from optimize.modelling import shapes

REPO = Path(__file__).resolve().parents[1]
TUNNEL = REPO / "configs" / "meshes" / "tunnel.off"


@pytest.fixture
def quad() -> Mesh:
    return Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2, 3]], name="quad")


@pytest.fixture
def grid3x3() -> Mesh:
    return shapes.grid(4, 4, size=(3.0, 3.0), name="grid3x3")


@pytest.fixture
def revolution() -> Mesh:
    return shapes.revolution(shapes.dome_profile(radius=10.0, rise=4.0, k=7), 16, name="dome")


@pytest.fixture
def perturbed_revolution(revolution) -> Mesh:
    return shapes.perturbed(revolution, 0.05, seed=7)


@pytest.fixture
def tunnel_path() -> Path:
    return TUNNEL


@pytest.fixture(scope="session")
def small_tunnel() -> Mesh:
    from optimize.modelling.designs import DESIGNS

    m = DESIGNS["tunnel"](subdivisions=1).mesh
    return m.with_vertices(m.V / 1000.0, name="small_tunnel")


@pytest.fixture(scope="session")
def cylinder_path(tmp_path_factory) -> Path:
    from optimize.mesh.io import write_mesh

    path = tmp_path_factory.mktemp("meshes") / "cylinder.obj"
    write_mesh(path, shapes.capped_cylinder())
    return path


@pytest.fixture
def rotation():
    """``rotation(seed) -> (3, 3)``: a seeded proper rotation matrix."""
    def make(seed: int) -> np.ndarray:
        q, r = np.linalg.qr(np.random.default_rng(seed).standard_normal((3, 3)))
        q = q * np.sign(np.diag(r))
        return q if np.linalg.det(q) > 0 else -q
    return make


IFC_DERIVED = "use_attribute_value_derived"


def _ifc_derived() -> bool | None:
    """ifcopenshell's ``use_attribute_value_derived`` (None while ifcopenshell is not imported)."""
    wrapper = getattr(sys.modules.get("ifcopenshell"), "ifcopenshell_wrapper", None)
    return None if wrapper is None else bool(wrapper.get_feature(IFC_DERIVED))


@pytest.fixture(autouse=True)
def _ifcopenshell_as_found():
    """A test that leaves ifcopenshell's ``use_attribute_value_derived`` switched (``ifcopenshell.validate``
    switches it on while it runs, for the whole process) fails, and the switch is put back: the tests
    after it read derived attributes as None (``get_info``), as they would alone, instead of failing
    far from the cause."""
    before = _ifc_derived()
    yield
    after = _ifc_derived()
    if after is not None and after != bool(before):
        sys.modules["ifcopenshell"].ifcopenshell_wrapper.set_feature(IFC_DERIVED, bool(before))
        pytest.fail(f"ifcopenshell's {IFC_DERIVED} was {bool(before)} before this test and {after} after it; "
                    "use fabricate.export.ifc.ifcopenshell_alone around ifcopenshell work", pytrace=False)


def pytest_addoption(parser, pluginmanager):
    """pyproject.toml's ``addopts`` name xdist's ``-n`` and ``--dist``; where xdist is not installed (the
    cadquery extra's environment) or is switched off (``-p no:xdist``) they are accepted and the tests run
    in this process."""
    if pluginmanager.hasplugin("xdist"):
        return
    group = parser.getgroup("xdist", "distributed testing (pytest-xdist is not loaded: ignored)")
    group._addoption("-n", "--numprocesses", dest="numprocesses", action="store", default=None,
                     help="ignored: pytest-xdist is not loaded")
    group.addoption("--dist", dest="dist", action="store", default="no", help="ignored: pytest-xdist is not loaded")
    group.addoption("--no-loadscope-reorder", dest="loadscopereorder", action="store_false",
                    help="ignored: pytest-xdist is not loaded")


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_auto_num_workers(config):
    """``-n auto``: one worker per core this process may run on (xdist's own count is psutil's physical
    cores, one on a machine with two hyperthreads)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Each test without an ``xdist_group`` mark goes in its file's group (xdist's ``loadgroup`` then keeps a
    file in one worker, as ``loadfile`` would); the tests of the session-wide quickstart run in one group of
    their own, so it runs once, not once per worker."""
    if not config.pluginmanager.hasplugin("xdist"):
        return
    for item in items:
        if item.get_closest_marker("xdist_group") is None:
            shared = "finished_run" in getattr(item, "fixturenames", ())
            item.add_marker(pytest.mark.xdist_group("quickstart" if shared else item.path.stem))
