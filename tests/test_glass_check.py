"""The glass check (issue 35 item 7): plate solutions against closed forms, EN 16612 laminate and
resistance, insulating units under a pressure change, the per-panel check and its CSV."""
import csv
import functools
from types import SimpleNamespace

import numpy as np
import pytest

from fabricate.structure.glass import (
    E_GLASS,
    NU_GLASS,
    GlassOptions,
    GlassPanels,
    check_glass,
    check_parts,
    design_strength,
    insulating_factor,
    isochore_pressure,
    kmod,
    laminate,
    plate_stiffness,
    share,
    write_glass_check,
)
from fabricate.structure.plate import solve_plate


def navier(a: float, b: float, nu: float, terms: int = 199) -> dict:
    """Navier's double series of the simply supported a x b plate under q = 1, D = 1 (Timoshenko &
    Woinowsky-Krieger section 30): centre deflection, centre moments, swept volume."""
    m = np.arange(1, terms + 1, 2)[:, None]
    n = np.arange(1, terms + 1, 2)[None, :]
    den = m * n * (m ** 2 / a ** 2 + n ** 2 / b ** 2) ** 2
    sign = np.sin(m * np.pi / 2) * np.sin(n * np.pi / 2)
    kx, ky = (m * np.pi / a) ** 2, (n * np.pi / b) ** 2
    c = 16 / np.pi ** 6
    return {"w": c * (sign / den).sum(), "Mx": c * (sign * (kx + nu * ky) / den).sum(),
            "My": c * (sign * (ky + nu * kx) / den).sum(),
            "V": 64 * a * b / np.pi ** 8 * (1 / (m ** 2 * n ** 2 * (m ** 2 / a ** 2 + n ** 2 / b ** 2) ** 2)).sum()}


def rectangle(a, b):
    return np.array([[0.0, 0.0], [a, 0.0], [a, b], [0.0, b]])


@pytest.mark.parametrize("ratio, alpha, beta", [(1.0, 0.00406, 0.0479), (2.0, 0.01013, 0.1017)])
def test_rectangle_against_navier(ratio, alpha, beta):
    """w_max = alpha q b^4 / D and M_max = beta q b^2 (Timoshenko Table 8, nu = 0.3) within 2 %."""
    b = 1000.0
    r = solve_plate(rectangle(ratio * b, b), 0.3)
    ref = navier(ratio * b, b, 0.3)
    assert ref["w"] / b ** 4 == pytest.approx(alpha, rel=2e-3)              # the series is Timoshenko's table
    assert max(ref["Mx"], ref["My"]) / b ** 2 == pytest.approx(beta, rel=2e-3)
    assert r.w_max == pytest.approx(ref["w"], rel=0.02)
    assert r.m_max == pytest.approx(max(ref["Mx"], ref["My"]), rel=0.02)
    assert r.volume == pytest.approx(ref["V"], rel=0.02)
    assert r.inradius == pytest.approx(b / 2) and r.area == pytest.approx(ratio * b * b)


def triangle_closed_form(a: float, nu: float):
    """The simply supported equilateral triangle of height ``a`` under q = 1, D = 1 (Timoshenko &
    Woinowsky-Krieger section 36): w = [x^3 - 3 x y^2 - a (x^2 + y^2) + 4 a^3 / 27] (4 a^2 / 9 - x^2 - y^2)
    / (64 a), origin at the centroid.  Returns the corners, the centre deflection a^4 / 972 and the
    largest principal moment magnitude on a fine grid of the closed form's exact second derivatives."""
    s = 2 * a / np.sqrt(3)
    P = np.array([[-a / 3, -s / 2], [2 * a / 3, 0.0], [-a / 3, s / 2]])
    u, v = np.meshgrid(np.linspace(0, 1, 401), np.linspace(0, 1, 401))
    inside = u + v <= 1
    X = P[0] + u[inside, None] * (P[1] - P[0]) + v[inside, None] * (P[2] - P[0])
    x, y = X[:, 0], X[:, 1]
    f = x ** 3 - 3 * x * y ** 2 - a * (x ** 2 + y ** 2) + 4 * a ** 3 / 27
    g = 4 * a ** 2 / 9 - x ** 2 - y ** 2
    fx, fy = 3 * x ** 2 - 3 * y ** 2 - 2 * a * x, -6 * x * y - 2 * a * y
    wxx = (6 * x - 2 * a) * g - 4 * x * fx - 2 * f
    wyy = (-6 * x - 2 * a) * g - 4 * y * fy - 2 * f
    wxy = -6 * y * g - 2 * y * fx - 2 * x * fy
    wxx, wyy, wxy = (d / (64 * a) for d in (wxx, wyy, wxy))
    Mx, My, Mxy = -(wxx + nu * wyy), -(wyy + nu * wxx), -(1 - nu) * wxy
    m = np.abs(Mx + My) / 2 + np.hypot((Mx - My) / 2, Mxy)
    return P, a ** 4 / 972, m.max()


def test_equilateral_triangle_closed_form():
    P, w0, m0 = triangle_closed_form(1000.0, NU_GLASS)
    r = solve_plate(P, NU_GLASS)
    assert r.w_max == pytest.approx(w0, rel=0.02)
    assert r.m_max == pytest.approx(m0, rel=0.02)
    assert r.inradius == pytest.approx(1000.0 / 3)


def test_plate_is_invariant_and_scales():
    """A rigid motion, a mirror image and the corner order change nothing; scaling by s scales w by s^4,
    moments by s^2, the volume by s^6 (q = D = 1)."""
    P = np.array([[0.0, 0.0], [1400.0, 100.0], [1300.0, 900.0], [200.0, 1000.0]])
    r = solve_plate(P, NU_GLASS)
    t = np.radians(37.0)
    R = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    moved = solve_plate(np.roll(P @ R.T + [5e5, -3e5], 1, axis=0)[::-1] * [-1.0, 1.0], NU_GLASS)
    for key in ("w_max", "m_max", "volume", "area", "inradius"):
        assert getattr(moved, key) == pytest.approx(getattr(r, key), rel=1e-6)
    big = solve_plate(2 * P, NU_GLASS)
    assert (big.w_max, big.m_max, big.volume) == pytest.approx((16 * r.w_max, 4 * r.m_max, 64 * r.volume), rel=1e-6)


def test_plate_rejects_a_reentrant_outline():
    from optimize.errors import MeshError

    with pytest.raises(MeshError, match="convex"):
        solve_plate(np.array([[0.0, 0], [1000, 0], [500, 200], [1000, 1000], [0, 1000]]), NU_GLASS)


def test_laminate_effective_thickness():
    """EN 16612 Annex D: no shear transfer -> the plies bend apart, full transfer (no interlayer) -> one
    pane of their sum; a two-ply 8 + 1.52 + 8 at omega = 0.1 by the closed formulas of two plies."""
    hw, hs = laminate((8.0, 8.0), 1.52, 0.0)
    assert hw == pytest.approx(np.cbrt(2 * 8.0 ** 3)) and hs == pytest.approx([np.sqrt(2 * 8.0 ** 2)] * 2)
    hw, hs = laminate((6.0, 10.0), 0.0, 1.0)
    assert hw == pytest.approx(16.0) and hs == pytest.approx([16.0, 16.0])
    h1, h2, hv, om = 8.0, 8.0, 1.52, 0.1
    h_s = 0.5 * (h1 + h2) + hv
    hs1, hs2 = h_s * h1 / (h1 + h2), h_s * h2 / (h1 + h2)
    hw_ref = np.cbrt(h1 ** 3 + h2 ** 3 + 12 * om * (h1 * hs2 ** 2 + h2 * hs1 ** 2))
    hw, hs = laminate((h1, h2), hv, om)
    assert hw == pytest.approx(hw_ref) and hs[0] == pytest.approx(np.sqrt(hw_ref ** 3 / (h1 + 2 * om * hs2)))


def test_kmod_and_design_strength():
    """k_mod = 0.663 t^(-1/16): 10 min wind 0.74, 50 years 0.29; f_g,d of float under wind 0.74 * 45 / 1.8,
    toughened adds (120 - 45) / 1.2, heat-strengthened (70 - 45) / 1.2, an enamelled toughened face (75 - 45)."""
    opt = GlassOptions()
    assert kmod(1 / 6) == pytest.approx(0.74, abs=0.005) and kmod(50 * 8760) == pytest.approx(0.29, abs=0.005)
    assert kmod(1e-4) == 1.0
    k = kmod(1 / 6)
    assert design_strength("float", k, opt) == pytest.approx(k * 25.0)
    assert design_strength("toughened", k, opt) == pytest.approx(k * 25.0 + 62.5)
    assert design_strength("heat-strengthened", k, opt) == pytest.approx(k * 25.0 + 25.0 / 1.2)
    assert design_strength("toughened", k, opt, enamelled=True) == pytest.approx(k * 25.0 + 25.0)


def test_two_pane_unit_under_a_pressure_change():
    """A square 6/16/6 unit: the insulating unit factor from the plate's swept volume is DIN 18008-1's
    phi = 1 / (1 + (a / a*)^4), a* = 28.9 (d_SZR d_a^3 d_i^3 / ((d_a^3 + d_i^3) B_V))^(1/4), B_V of the
    square from Navier's series (0.0194); the panes' loads satisfy the linearized gas law
    (p - p0) V = -p_atm dV and carry phi p0 each."""
    a, d, cav, p_atm = 1000.0, 6.0, 16.0, 100.0
    r = solve_plate(rectangle(a, a), NU_GLASS)
    D = plate_stiffness(d)
    phi = insulating_factor(r.volume, r.area, cav, D, D, p_atm)
    B_v = navier(a, a, NU_GLASS)["V"] * 12 * (1 - NU_GLASS ** 2) / (a ** 4 * a * a)
    assert B_v == pytest.approx(0.0194, abs=2e-4)
    a_star = (E_GLASS / (p_atm * 1e-3)) ** 0.25 * (cav * d ** 6 / (2 * d ** 3 * B_v)) ** 0.25
    assert (E_GLASS / 0.1) ** 0.25 == pytest.approx(28.9, abs=0.05)
    assert phi == pytest.approx(1 / (1 + (a / a_star) ** 4), rel=0.02)
    p0 = isochore_pressure(20.0, -2.0, 600.0) * 1e-3                                 # summer, N/mm2
    assert p0 * 1e3 == pytest.approx(16.0)
    q_o, q_i = share(0.0, 0.0, p0, 0.5, phi)
    assert (q_o, q_i) == pytest.approx((-phi * p0, phi * p0))
    dp = q_i                                                                         # the cavity over-pressure
    dV = (-q_o + q_i) * r.volume / D                                                 # both panes bulge out
    assert dp - p0 == pytest.approx(-p_atm * 1e-3 * dV / (a * a * cav), rel=1e-9)
    q_o, q_i = share(1e-3, 0.0, 0.0, 0.5, phi)                                      # wind on the outer pane
    assert (q_o, q_i) == pytest.approx((0.5e-3 * (1 + phi), 0.5e-3 * (1 - phi)))


LOADS = SimpleNamespace(glass_unit_weight=25.0, snow=1.0, wind_pressure=0.0, wind_suction=0.0, finishes=0.5)
SNOW_ONLY = [("ULS 1.5S", "uls", {"snow": 1.5, "self_weight": 1.35}), ("SLS S", "sls", {"snow": 1.0})]


def one_panel(outline, inward=(0.0, 0.0, -1.0)):
    return GlassPanels(("P0001",), (np.asarray(outline, float),), np.array([inward], float), np.array([0]))


def test_check_of_a_monolithic_roof_panel_matches_the_closed_form():
    """A horizontal 1500 x 1000, 10 mm float panel under 1.5 x 1 kN/m2 of snow: stress 6 beta q b^2 / h^2,
    deflection alpha q b^4 / D (Navier), utilization against f_g,d with k_mod of 3 weeks, limit b / 100."""
    from fabricate.cad.glass import BuildUp

    bu = BuildUp.from_config({"type": "monolithic", "thickness_mm": 10, "treatment": "float"})
    c = check_glass(one_panel(rectangle(1500.0, 1000.0)), bu, LOADS, SNOW_ONLY, GlassOptions())
    ref = navier(1500.0, 1000.0, NU_GLASS)
    sigma = 6 * 1.5e-3 * max(ref["Mx"], ref["My"]) / 10.0 ** 2
    assert c.sigma_mpa[0] == pytest.approx(sigma, rel=0.02)
    assert c.f_gd_mpa[0] == pytest.approx(kmod(504.0) * 25.0)
    assert c.utilization_stress[0] == pytest.approx(sigma / (kmod(504.0) * 25.0), rel=0.02)
    assert c.deflection_mm[0] == pytest.approx(1e-3 * ref["w"] / plate_stiffness(10.0), rel=0.02)
    assert c.deflection_limit_mm[0] == pytest.approx(10.0)
    rep = c.report()
    assert rep["worst"]["id"] == "P0001" and rep["not_on_glass"] == ["self_weight"]
    assert c.overhead[0] and any("laminated safety glass" in n for n in c.notes[0])


def test_snow_only_on_an_upward_outer_face_and_k_mod_of_the_shortest_load():
    """A vertical panel carries no snow (the combination's k_mod is then the permanent one, not snow's);
    a panel hanging under its beams (outer face down) neither."""
    from fabricate.cad.glass import BuildUp

    bu = BuildUp.monolithic(10.0)
    combos = [("ULS G + S", "uls", {"glass": 1.0, "snow": 1.5}), ("SLS G", "sls", {"glass": 1.0})]
    flat = check_glass(one_panel(rectangle(1000.0, 1000.0)), bu, LOADS, combos)
    hung = check_glass(one_panel(rectangle(1000.0, 1000.0), (0.0, 0.0, 1.0)), bu, LOADS, combos)
    wall = check_glass(one_panel(rectangle(1000.0, 1000.0), (1.0, 0.0, 0.0)), bu, LOADS, combos)
    assert flat.k_mod[0] == pytest.approx(kmod(504.0)) and hung.k_mod[0] == pytest.approx(kmod(438000.0))
    assert hung.sigma_mpa[0] < flat.sigma_mpa[0] / 5 and wall.sigma_mpa[0] == 0.0
    assert not wall.overhead[0] and wall.notes[0] == ()


def test_heat_treatment_per_ply_decides_the_governing_ply():
    """88.4 with a float lower ply and a toughened upper one: both plies see the same stress (equal
    plies), the float ply governs; its design strength has no prestress term."""
    from fabricate.cad.glass import BuildUp

    bu = BuildUp.from_config({"type": "laminated", "plies_mm": [8, 8], "interlayer_mm": 1.52,
                              "treatment": ["toughened", "float"]})
    c = check_glass(one_panel(rectangle(1500.0, 1000.0)), bu, LOADS, SNOW_ONLY)
    assert c.ply[0] == "pane ply 2" and c.treatment[0] == "float"
    assert c.f_gd_mpa[0] == pytest.approx(kmod(504.0) * 25.0)
    # PVB is family 1: no shear transfer under snow, each ply carries half the moment
    ref = navier(1500.0, 1000.0, NU_GLASS)
    assert c.sigma_mpa[0] == pytest.approx(6 * 1.5e-3 * max(ref["Mx"], ref["My"]) / 2 / 8.0 ** 2, rel=0.02)
    assert any("post-breakage" in n for n in c.notes[0])


def test_insulated_unit_gets_climatic_combinations():
    from fabricate.cad.glass import BuildUp

    bu = BuildUp.from_config({"type": "insulated", "outer": {"type": "monolithic", "thickness_mm": 6},
                              "inner": {"type": "monolithic", "thickness_mm": 6}, "cavity_mm": 16})
    c = check_glass(one_panel(rectangle(1000.0, 1000.0), (1.0, 0.0, 0.0)), bu, LOADS,
                    [("ULS W", "uls", {"wind_pressure": 1.5}), ("SLS W", "sls", {"wind_pressure": 1.0})])
    rep = c.report()
    assert rep["climate"]["p0_summer_kpa"] == pytest.approx(16.0)
    assert rep["climate"]["p0_winter_kpa"] == pytest.approx(-16.1)
    # no wind load: the climatic load governs, 1.5 phi p0 on either pane, k_mod of the climatic duration
    r = solve_plate(rectangle(1000.0, 1000.0), NU_GLASS)
    phi = insulating_factor(r.volume, r.area, 16.0, plate_stiffness(6.0), plate_stiffness(6.0), 100.0)
    assert c.sigma_mpa[0] == pytest.approx(6 * 1.5 * phi * 16.1e-3 * r.m_max / 36.0, rel=1e-6)
    assert c.k_mod[0] == pytest.approx(kmod(11.0)) and "winter" in c.uls[0]
    assert c.phi[0] == pytest.approx(phi)


def test_options_name_the_bad_key():
    from optimize.errors import ConfigError

    with pytest.raises(ConfigError, match="structure.glass.consequence_class"):
        GlassOptions(consequence_class="CC4")
    with pytest.raises(ConfigError, match="site_altitude"):
        GlassOptions(site_altitude=500.0)
    assert GlassOptions(site_altitude=800.0, production_altitude=200.0).altitude_change() == (600.0, 600.0)


@functools.lru_cache(maxsize=None)
def flat_roof():
    """Two horizontal 1500 x 1000 mm faces, beams 200 mm below: built parts."""
    from optimize.mesh import Mesh

    from fabricate.cad import PartSpec, build_parts
    from fabricate.offset import offset_structure

    V = np.array([[0.0, 0, 0], [1500, 0, 0], [3000, 0, 0], [0, 1000, 0], [1500, 1000, 0], [3000, 1000, 0]])
    F = [[0, 1, 4, 3], [1, 2, 5, 4]]
    return build_parts(offset_structure(Mesh(V, F), (0.0, -200.0)),
                       PartSpec(glass={"type": "laminated", "plies_mm": [8, 8], "interlayer_mm": 1.52}))


def test_check_parts_and_the_csv_round_trip(tmp_path):
    """From built parts: one plate solve for two congruent panels, the bearing face's normal toward the
    beams (self-weight pushes the glass onto them), every unit a CSV row with its figures."""
    from fabricate.structure.options import StructureOptions

    parts = flat_roof()
    c = check_parts(parts, StructureOptions())
    assert c.ids == ("P0001", "P0002") and c.facts["plate_solves"] == 1
    assert np.allclose(c.tilt_deg, 90.0) and c.overhead.all()
    g = parts.of_kind("panel")[-1]
    w, h = np.ptp(g.flat[0], axis=0)
    assert c.span_mm[0] == pytest.approx(min(w, h), rel=1e-6)
    facts = write_glass_check(c, tmp_path / "glass_check.csv")
    with open(tmp_path / "glass_check.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert facts["rows"] == len(rows) == 2
    for i, row in enumerate(rows):
        assert row["id"] == c.ids[i] and float(row["utilization"]) == pytest.approx(c.utilization[i], abs=1e-4)
        assert row["build_up"] == "88.4" and row["overhead"] == "yes" and row["uls"] == c.uls[i]
    assert c.per_unit()["P0001"]["utilization"] == pytest.approx(c.utilization[0])
    m = c.measures()
    assert m["glass_stress"]["count"] == 2 and m["glass_stress"]["pass"]
    assert {w["panel"] for w in m["glass_deflection"]["worst"]} == {0, 1}
