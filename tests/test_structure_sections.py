"""Closed-form section properties against a direct numerical integration of the shape (within 1%)."""
from __future__ import annotations

import numpy as np
import pytest

from fabricate.structure.sections import i_section, plate, rhs, section, tee
from optimize.errors import ConfigError


def raster(inside, h, b, n=1200):
    """A, centroid from the top, Iy (about the horizontal centroidal axis), Iz of the region
    ``inside(y, z)`` (y down from the top fibre, z across), integrated on an n x n midpoint grid."""
    y = (np.arange(n) + 0.5) / n * h
    z = (np.arange(n) - n / 2 + 0.5) / n * b
    Y, Z = np.meshgrid(y, z, indexing="ij")
    m = inside(Y, Z)
    dA = (h / n) * (b / n)
    A = m.sum() * dA
    c = (Y * m).sum() * dA / A
    return A, c, (((Y - c) ** 2) * m).sum() * dA, ((Z ** 2) * m).sum() * dA


CASES = [
    (plate(60, 200), lambda Y, Z: np.ones_like(Y, bool)),
    (rhs(300, 150, 8), lambda Y, Z: ~((Y > 8) & (Y < 292) & (np.abs(Z) < 75 - 8))),
    (i_section(300, 150, 7.1, 10.7), lambda Y, Z: (Y < 10.7) | (Y > 300 - 10.7) | (np.abs(Z) < 7.1 / 2)),
    (tee(200, 120, 10, 15), lambda Y, Z: (Y < 15) | (np.abs(Z) < 5)),
]


@pytest.mark.parametrize("sec, inside", CASES, ids=[c[0].shape for c in CASES])
def test_area_centroid_and_inertias_match_integration(sec, inside):
    A, c, Iy, Iz = raster(inside, sec.h, sec.b)
    assert sec.A == pytest.approx(A, rel=0.01)
    assert sec.centroid == pytest.approx(c, rel=0.01)
    assert sec.Iy == pytest.approx(Iy, rel=0.01)
    assert sec.Iz == pytest.approx(Iz, rel=0.01)
    assert sec.Wy == pytest.approx(Iy / max(c, sec.h - c), rel=0.01)
    assert sec.Wz == pytest.approx(Iz / (sec.b / 2), rel=0.01)


def test_torsion_constants_against_known_values():
    # square: J = 0.1406 a^4 (Roark); thin plate: J -> h t^3 / 3 (1 - 0.63 t / h)
    assert plate(100, 100).J == pytest.approx(0.1406 * 100 ** 4, rel=0.01)
    assert plate(10, 400).J == pytest.approx(400 * 10 ** 3 / 3 * (1 - 0.63 * 10 / 400), rel=0.01)
    # thin-walled tube: Bredt 4 A_m^2 t / perimeter of the mid-line
    t = 5.0
    assert rhs(200, 100, t).J == pytest.approx(4 * (195 * 95) ** 2 * t / (2 * (195 + 95)), rel=1e-9)


def test_strong_axis_is_the_depth_in_the_beam_plane_and_mass_follows_the_area():
    s = plate(80, 300)
    assert s.Iy > s.Iz and s.Iy == pytest.approx(80 * 300 ** 3 / 12)
    assert s.mass_per_m(7850) == pytest.approx(80 * 300 * 1e-6 * 7850)
    assert s.name == "plate 80x300"


@pytest.mark.parametrize("kwargs, key", [
    (dict(shape="rhs", depth=100, width=50), "structure.section.web"),
    (dict(shape="rhs", depth=100, width=50, web=30), "structure.section.web"),
    (dict(shape="i", depth=100, width=50, web=5, flange=60), "structure.section.flange"),
    (dict(shape="plate", depth=-1, width=50), "structure.section.depth"),
    (dict(shape="angle", depth=100, width=50), "structure.section.shape"),
])
def test_impossible_sections_name_the_key(kwargs, key):
    with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
        section(**kwargs)
