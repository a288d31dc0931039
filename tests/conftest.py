"""Shared fixtures: tiny hand-made meshes and the real meshes in ``../shared/data``.

- ``quad``: one planar unit square (counter-clockwise seen from +z).
- ``grid3x3``: 3 x 3 planar quads on 4 x 4 vertices (4 interior valence-4 vertices).
- ``revolution``: a dome of revolution, meridians x parallels: planar, conical and
  circular by construction; ``perturbed_revolution``: the same with seeded noise.
- ``halftunnel_path``, ``cylinder_path``: the shared real meshes (``shared/data``
  beside the repository, or beside the one it was cloned from); a missing file
  fails the test with the path it looked for (never a silent skip).
- ``rotation``: ``rotation(seed)`` gives a seeded (3, 3) rotation matrix.
"""
from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest

from optimize import Mesh, shapes

REPO = Path(__file__).resolve().parents[1]


def _shared_data() -> Path:
    """``shared/data`` beside the repository (as CI lays it out) or, in a clone made
    elsewhere (``git clone . $(mktemp -d)``), beside the repository it was cloned from."""
    here = REPO.parent / "shared" / "data"
    if here.is_dir():
        return here
    try:
        origin = subprocess.run(["git", "-C", str(REPO), "config", "--get", "remote.origin.url"],
                                capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        origin = ""
    if origin and Path(origin).is_dir():
        there = Path(origin).resolve().parent / "shared" / "data"
        if there.is_dir():
            return there
    return here  # missing: shared_file says where it looked


SHARED_DATA = _shared_data()


def shared_file(name: str) -> Path:
    """Path of a file in ``../shared/data``; fails (not skips) when it is missing."""
    path = SHARED_DATA / name
    if not path.is_file():
        pytest.fail(f"shared mesh {path} is missing: the repository's parent folder must hold "
                    "shared/data/ (see shared/data/README.md)", pytrace=False)
    return path


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
def halftunnel_path() -> Path:
    return shared_file("halftunnel.off")


@pytest.fixture
def cylinder_path() -> Path:
    return shared_file("cylinder.obj")


@pytest.fixture
def rotation():
    """``rotation(seed) -> (3, 3)``: a seeded proper rotation matrix."""
    def make(seed: int) -> np.ndarray:
        q, r = np.linalg.qr(np.random.default_rng(seed).standard_normal((3, 3)))
        q = q * np.sign(np.diag(r))
        return q if np.linalg.det(q) > 0 else -q
    return make
