"""The load model: tributary split of a panel (straight skeleton), a uniform temperature change on a
held member (N = -E A alpha dT), the hubs' weight at their nodes, maintenance and the consequence
class in the generated EN 1990 combinations.  Units: mm, N, MPa."""
from __future__ import annotations

import numpy as np
import pytest

from optimize.mesh import Mesh

from fabricate.structure.engine import solve
from fabricate.structure.frame import Frame
from fabricate.structure.loads import ALPHA_STEEL, node_weights, thermal_case, tributary_shares
from fabricate.structure.options import KFI, default_combinations
from fabricate.structure.sections import plate

E, G = 210000.0, 81000.0
SEC = plate(60.0, 200.0)


def test_a_rectangle_sends_the_45_degree_triangle_to_its_short_edges_and_a_triangle_by_edge_length():
    a, b = 3.0, 1.0
    m = Mesh(np.array([[0, 0, 0], [a, 0, 0], [a, b, 0], [0, b, 0], [a + 1, 0, 0.0]]), [[0, 1, 2, 3], [1, 4, 2, -1]])
    s = tributary_shares(m)
    np.testing.assert_allclose(s[:4], [(a * b - b * b / 2) / 2 / (a * b), b * b / 4 / (a * b)] * 2, rtol=1e-12)
    ell = np.array([1.0, np.sqrt(2.0), 1.0])
    np.testing.assert_allclose(s[4:], ell / ell.sum(), rtol=1e-12)      # a triangle: its incircle's fan


def test_a_held_member_warmed_by_dT_carries_minus_E_A_alpha_dT_and_a_free_one_nothing():
    X = np.array([[0.0, 0, 0], [4000.0, 0, 0]])
    for fixed_end, N_expected in ((True, -E * SEC.A * ALPHA_STEEL * 30.0), (False, 0.0)):
        fx = np.zeros((2, 6), dtype=bool)
        fx[0] = True
        fx[1, :3] = fixed_end                 # held along the member (its rotations free)
        fr = Frame(X, np.array([[0, 1]]), np.array([[0.0, 1.0, 0.0]]), (SEC,), np.zeros(1, dtype=np.int64), E, G, fx)
        sol = solve(fr, {"t": thermal_case(fr, 30.0, "t")})
        F = sol.end_forces["t"]
        assert -F[0, 0] == pytest.approx(N_expected, abs=1e-6 * E * SEC.A * ALPHA_STEEL * 30.0)
        if not fixed_end:
            assert sol.displacements["t"][1, 0] == pytest.approx(4000.0 * ALPHA_STEEL * 30.0, rel=1e-9)


def test_the_hubs_weigh_on_their_own_nodes():
    class Group:
        element = np.array([0, 2, 2])
        volume_mm3 = np.array([1e6, 2e6, 3e6])

    class Parts:
        def of_kind(self, kind):
            return [Group()] if kind == "node" else []

    w = node_weights(Parts(), 4, 78.5)
    np.testing.assert_allclose(w, [78.5e-6 * 1e6, 0.0, 78.5e-6 * 5e6, 0.0])
    assert not node_weights(None, 4, 78.5).any()


def test_the_consequence_class_scales_the_unfavourable_factors_and_maintenance_stands_alone():
    cc3 = {n: f for n, k, f in default_combinations(KFI["CC3"])}
    cc2 = {n: f for n, k, f in default_combinations(KFI["CC2"])}
    lead_snow = next(f for n, f in cc3.items() if n.startswith("ULS") and "S +" in n and "T" not in n)
    assert lead_snow["self_weight"] == pytest.approx(1.35 * 1.1) and lead_snow["snow"] == pytest.approx(1.65)
    uplift3 = next(f for n, f in cc3.items() if "uplift" in n and n.startswith("ULS"))
    assert uplift3["self_weight"] == 1.0                                    # favourable: no K_FI
    maint = next(f for n, f in cc2.items() if "maintenance" in n and n.startswith("ULS"))
    assert maint["maintenance"] == 1.5 and not {"snow", "wind_pressure", "wind_suction"} & set(maint)
    temps = [n for n in cc2 if "T rise" in n or "T fall" in n]
    assert len(temps) == 2
    assert not any("maintenance" in n or "T " in n for n, _, _ in default_combinations(1.0, False, False))
