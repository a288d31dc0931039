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


# -- section class under N + M (EN 1993-1-1 Table 5.2; outstands: kσ of EN 1993-1-5 Table 4.2) ----------
EPS = np.sqrt(235.0 / 355.0)  # S355


def test_rhs_web_in_pure_bending_is_class_1_and_in_pure_compression_class_4():
    from fabricate.structure.sections import classify

    s = rhs(200, 40, 4)                       # web c = h - 3t = 188, c/t = 47 (flanges c/t = 7)
    bend = classify(s, 355.0, np.array([0.0]), np.array([20e6]))
    assert bend.cls[0] == 1 and bend.part[0] == "web"
    assert bend.alpha[0] == pytest.approx(0.5) and bend.psi[0] == pytest.approx(-1.0)
    assert bend.limit[0] == pytest.approx(124 * EPS) and bend.ratio[0] == pytest.approx(47 / (124 * EPS))
    comp = classify(s, 355.0, np.array([-100e3]), np.array([0.0]))   # 100 kN compression
    assert comp.cls[0] == 4 and comp.limit[0] == pytest.approx(42 * EPS)
    assert comp.ratio[0] == pytest.approx(47 / (42 * EPS))            # 1.375: class 4
    assert comp.alpha[0] == pytest.approx(1.0) and comp.psi[0] == pytest.approx(1.0)
    pull = classify(s, 355.0, np.array([+100e3]), np.array([0.0]))   # tension: nothing buckles
    assert pull.cls[0] == 1 and pull.ratio[0] == 0.0


def test_rhs_web_under_compression_and_bending_uses_alpha_and_psi():
    from fabricate.structure.sections import classify

    s, t, h, b = rhs(200, 60, 4), 4.0, 200.0, 60.0   # flanges c/t = 12: the web governs
    c = h - 3 * t
    # the plastic neutral axis 40 mm below mid-depth: the webs (2t thick) carry N = 2 a (2t) fy, the rest M
    a, fy = 40.0, 100.0                              # any scale: the ratio N / M fixes the axis
    Wpl = b * h ** 2 / 4 - (b - 2 * t) * (h - 2 * t) ** 2 / 4
    N, M = -2 * a * 2 * t * fy, fy * (Wpl - 2 * t * a ** 2)
    alpha = (h / 2 + a - (h - c) / 2) / c            # the compressed part of c: 134 / 188
    sig = [-N / s.A + M * (c / 2) / s.Iy, -N / s.A - M * (c / 2) / s.Iy]   # web ends, compression +
    psi = sig[1] / sig[0]
    l1, l2 = 396 * EPS / (13 * alpha - 1), 456 * EPS / (13 * alpha - 1)
    l3 = 42 * EPS / (0.67 + 0.33 * psi)
    assert l2 < c / t <= l3                          # 44.9 < 47 <= 69.9: class 3 by hand
    got = classify(s, 355.0, np.array([N]), np.array([M]))
    assert got.alpha[0] == pytest.approx(alpha, rel=1e-6) and got.psi[0] == pytest.approx(psi, rel=1e-9)
    assert got.cls[0] == 3 and got.limit[0] == pytest.approx(l3, rel=1e-9)
    assert l1 < l2
    flipped = classify(s, 355.0, np.array([N]), np.array([-M]))   # doubly symmetric: the sign of M does not matter
    assert flipped.cls[0] == 3 and flipped.ratio[0] == pytest.approx(got.ratio[0])


def test_tee_stem_is_an_outstand_class_4_when_its_tip_is_compressed():
    from fabricate.structure.sections import classify

    # sagging (the flange side compressed, the tip in tension): psi = sigma_tip / sigma_root < -1: k = 23.8
    narrow = tee(200, 30, 10, 12)                  # a narrow flange (c/t 0.8), so that the stem governs
    zc = narrow.centroid                           # (360 x 6 + 1880 x 106) / 2240 = 89.9 mm below the top
    sag = classify(narrow, 355.0, np.array([0.0]), np.array([10e6]))
    assert sag.part[0] == "stem" and sag.psi[0] == pytest.approx(-(200 - zc) / (zc - 12), rel=1e-9)
    assert sag.limit[0] == pytest.approx(21 * EPS * np.sqrt(23.8))
    # plastic axis of pure bending: half the area above, 360 + 10 (u - 12) = 1120 -> u = 88
    alpha = (88 - 12) / 188
    assert sag.alpha[0] == pytest.approx(alpha, rel=1e-6)
    assert sag.cls[0] == 1 and 18.8 <= 9 * EPS / (alpha * np.sqrt(alpha))
    s = tee(200, 100, 10, 12)                      # the quickstart's T: stem c/t = 188 / 10 = 18.8
    zc = s.centroid                                # 67.04 mm below the top
    # hogging (the tip compressed): psi = sigma_root / sigma_tip, k = 0.57 - 0.21 psi + 0.07 psi^2
    hog = classify(s, 355.0, np.array([0.0]), np.array([-10e6]))
    psi = -(zc - 12) / (200 - zc)
    k = 0.57 - 0.21 * psi + 0.07 * psi ** 2
    assert hog.psi[0] == pytest.approx(psi, rel=1e-9)
    assert hog.limit[0] == pytest.approx(21 * EPS * np.sqrt(k), rel=1e-9)
    assert hog.cls[0] == 4 and hog.part[0] == "stem" and hog.ratio[0] == pytest.approx(18.8 / hog.limit[0])
    assert hog.alpha[0] == pytest.approx((200 - 46) / 188, rel=1e-6)   # compressed below the axis at 46
    comp = classify(s, 355.0, np.array([-50e3]), np.array([0.0]))
    assert comp.cls[0] == 4 and comp.limit[0] == pytest.approx(14 * EPS)
    thick = classify(tee(200, 100, 17, 12), 355.0, np.array([-50e3, 0.0]), np.array([0.0, -10e6]))
    assert (thick.cls <= 3).all()                  # c/t = 188 / 17 = 11.1 <= 14 eps = 11.4


def test_solid_plates_have_no_class_and_flanges_count_when_compressed():
    from fabricate.structure.sections import classify

    p = classify(plate(20, 300), 355.0, np.array([-1e5]), np.array([1e7]))
    assert p.cls[0] == 1 and p.ratio[0] == 0.0
    wide = i_section(300, 300, 10, 8)               # flange outstand (300 - 10) / 2 / 8 = 18.1 > 14 eps
    got = classify(wide, 355.0, np.array([0.0, -1e5]), np.array([1e7, 0.0]))
    assert (got.cls == 4).all() and set(got.part) == {"flange"}
    assert classify(wide, 355.0, np.array([1e6]), np.array([0.0])).cls[0] == 1   # all in tension


@pytest.mark.parametrize("sec", [rhs(300, 100, 5), tee(200, 100, 10, 12), i_section(300, 150, 7.1, 10.7),
                                 plate(60, 200)], ids=lambda s: s.shape)
def test_the_plastic_axis_carries_the_loads_in_their_proportion(sec):
    from fabricate.structure.sections import plastic_axis

    rng = np.random.default_rng(7)
    N, M = rng.normal(0, 1e5, 400), rng.normal(0, 1e7, 400)
    u = plastic_axis(sec, N, M)
    z = (np.arange(4000) + 0.5) / 4000 * sec.h       # the section in thin slices down its depth
    flange = (z < sec.tf) | ((z > sec.h - sec.tf) & (sec.shape in ("rhs", "i")))
    web = {"plate": sec.b, "rhs": 2 * sec.tw, "i": sec.tw, "tee": sec.tw}[sec.shape]
    dA = np.where(flange & (sec.shape != "plate"), sec.b, web) * sec.h / 4000
    above = np.clip((u[:, None] - z[None]) / (sec.h / 4000) + 0.5, 0.0, 1.0)    # the part of a slice above u
    sig = np.where(M[:, None] >= 0, 2 * above - 1, 1 - 2 * above)                  # fully plastic, compression +
    Np, Mp = (sig * dA).sum(axis=1), (sig * dA * (sec.centroid - z)).sum(axis=1) / sec.h
    # the plastic pair (Np, Mp) points along (-N, M): the sine of the angle between them vanishes
    m = M / sec.h
    sine = (Np * m - Mp * -N) / (np.hypot(Np, Mp) * np.hypot(N, m))
    assert np.abs(sine).max() < 3e-3                # the slices straddle the flanges: 0.1 % of their area
    assert (Np * -N + Mp * m > 0).all()
