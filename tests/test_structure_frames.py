"""The OpenSees frame against closed-form beam theory (within 1%) and a second engine (PyNite).

Every solved model also balances: the reactions sum to minus the loads (1e-6 relative).
Units: mm, N, MPa.  Sections: a 60 x 200 plate (strong axis in the beam plane).
"""
from __future__ import annotations

import numpy as np
import pytest

from fabricate.structure.engine import MechanismError, solve
from fabricate.structure.frame import Frame
from fabricate.structure.loads import LoadCase
from fabricate.structure.results import chord_deflection, equilibrium, internal_forces
from fabricate.structure.sections import plate

E, G = 210000.0, 81000.0
SEC = plate(60.0, 200.0)
EI = E * SEC.Iy            # strong axis: bending in the beam plane
L = 4000.0


def frame(X, elements, fixed, normal=(0.0, 1.0, 0.0), pinned=False) -> Frame:
    X = np.asarray(X, dtype=float)
    elements = np.asarray(elements, dtype=np.int64)
    fx = np.zeros((len(X), 6), dtype=bool)
    for i, dofs in fixed.items():
        fx[i, list(dofs)] = True
    return Frame(X, elements, np.tile(normal, (len(elements), 1)).astype(float), (SEC,),
                 np.zeros(len(elements), dtype=np.int64), E, G, fx, pinned=pinned,
                 ids=tuple(f"B{i + 1}" for i in range(len(elements))))


def case(fr: Frame, nodal=None, line=None) -> LoadCase:
    n, e = fr.n_nodes, fr.n_elements
    N = np.zeros((n, 6))
    for i, f in (nodal or {}).items():
        N[i, :len(f)] = f
    W = np.zeros((e, 3)) if line is None else np.broadcast_to(np.asarray(line, dtype=float), (e, 3)).copy()
    return LoadCase("c", N, W)


def run(fr, c):
    sol = solve(fr, {"c": c})
    res = equilibrium(fr, {"c": c}, sol)["c"]
    assert res < 1e-6, f"reactions do not balance the loads: relative residual {res:.2e}"
    return sol


def moments(fr, sol):
    """Max |strong-axis moment| per element (N mm), from the end forces and line loads."""
    _, _, Ms, _, _ = internal_forces(sol.end_forces["c"], sol.line_local["c"], fr.lengths())
    return np.abs(Ms).max(axis=1)


PIN, ROLLER, FIX = (0, 1, 2, 3), (1, 2), (0, 1, 2, 3, 4, 5)


def test_cantilever_point_load_tip_deflection_and_root_moment():
    P = 5000.0
    fr = frame([[0, 0, 0], [L, 0, 0]], [[0, 1]], {0: FIX})
    sol = run(fr, case(fr, nodal={1: (0, 0, -P)}))
    assert sol.displacements["c"][1, 2] == pytest.approx(-P * L ** 3 / (3 * EI), rel=0.01)
    assert moments(fr, sol)[0] == pytest.approx(P * L, rel=0.01)


def test_cantilever_uniform_load_tip_deflection_and_root_moment():
    q = 3.0
    fr = frame([[0, 0, 0], [L, 0, 0]], [[0, 1]], {0: FIX})
    sol = run(fr, case(fr, line=(0, 0, -q)))
    assert sol.displacements["c"][1, 2] == pytest.approx(-q * L ** 4 / (8 * EI), rel=0.01)
    assert moments(fr, sol)[0] == pytest.approx(q * L ** 2 / 2, rel=0.01)


def test_simply_supported_uniform_load_midspan_deflection_and_moment_in_one_element():
    q = 2.0
    fr = frame([[0, 0, 0], [L, 0, 0]], [[0, 1]], {0: PIN, 1: ROLLER})
    sol = run(fr, case(fr, line=(0, 0, -q)))
    assert moments(fr, sol)[0] == pytest.approx(q * L ** 2 / 8, rel=0.01)
    d = chord_deflection(sol.end_forces["c"], sol.line_local["c"], fr.lengths(), np.array([EI]),
                         np.array([E * SEC.Iz]))
    assert d[0] == pytest.approx(5 * q * L ** 4 / (384 * EI), rel=0.01)


def test_simply_supported_point_load_at_midspan():
    P = 8000.0
    fr = frame([[0, 0, 0], [L / 2, 0, 0], [L, 0, 0]], [[0, 1], [1, 2]], {0: PIN, 2: ROLLER})
    sol = run(fr, case(fr, nodal={1: (0, 0, -P)}))
    assert sol.displacements["c"][1, 2] == pytest.approx(-P * L ** 3 / (48 * EI), rel=0.01)
    assert moments(fr, sol).max() == pytest.approx(P * L / 4, rel=0.01)


def test_weak_axis_bending_uses_the_weak_moment_of_inertia():
    P = 500.0
    fr = frame([[0, 0, 0], [L, 0, 0]], [[0, 1]], {0: FIX}, normal=(0.0, 0.0, 1.0))  # beam plane = x-y
    sol = run(fr, case(fr, nodal={1: (0, 0, -P)}))
    assert sol.displacements["c"][1, 2] == pytest.approx(-P * L ** 3 / (3 * E * SEC.Iz), rel=0.01)


def test_two_beam_portal_tip_deflection_and_base_moment():
    """An L-shaped portal: a column of height h fixed at its foot, a beam of length a, a load P at the
    tip: delta = P a^3 / (3 EI) + P a^2 h / EI (+ the column's shortening P h / (E A))."""
    h, a, P = 3000.0, 2500.0, 4000.0
    fr = frame([[0, 0, 0], [0, 0, h], [a, 0, h]], [[0, 1], [1, 2]], {0: FIX})
    sol = run(fr, case(fr, nodal={2: (0, 0, -P)}))
    expect = P * a ** 3 / (3 * EI) + P * a ** 2 * h / EI + P * h / (E * SEC.A)
    assert -sol.displacements["c"][2, 2] == pytest.approx(expect, rel=0.01)
    assert moments(fr, sol)[0] == pytest.approx(P * a, rel=0.01)
    assert sol.reactions["c"][0, 4] == pytest.approx(-P * a, rel=0.01)  # the foot's moment about y


def test_loads_that_scale_linearly_scale_every_result_linearly():
    fr = frame([[0, 0, 0], [0, 0, 3000], [2500, 0, 3000]], [[0, 1], [1, 2]], {0: FIX})
    c1 = case(fr, nodal={2: (300, -200, -4000)}, line=(0.5, 0.2, -1.5))
    s1, s3 = run(fr, c1), run(fr, c1.scaled(3.0))
    np.testing.assert_allclose(s3.displacements["c"], 3 * s1.displacements["c"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(s3.end_forces["c"], 3 * s1.end_forces["c"], rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(s3.reactions["c"], 3 * s1.reactions["c"], rtol=1e-9, atol=1e-6)


def test_a_mechanism_is_an_error_not_a_result():
    fr = frame([[0, 0, 0], [L, 0, 0]], [[0, 1]], {0: PIN})  # a pin alone: the beam swings
    with pytest.raises(MechanismError, match="mechanism"):
        solve(fr, {"c": case(fr, nodal={1: (0, 0, -1000)})})
    fr = frame([[0, 0, 0], [L, 0, 0]], [[0, 1]], {0: FIX}, pinned=True)  # released joints
    with pytest.raises(MechanismError, match="pinned"):
        solve(fr, {"c": case(fr, nodal={1: (0, 0, -1000)})})


def _grid(nx=4, ny=3, a=1500.0):
    """A plane grid of ``nx`` x ``ny`` bays in z = 0 (beams in vertical planes), corners pinned."""
    X = np.array([[i * a, j * a, 0.0] for j in range(ny + 1) for i in range(nx + 1)])
    idx = lambda i, j: j * (nx + 1) + i  # noqa: E731
    E_ = [(idx(i, j), idx(i + 1, j)) for j in range(ny + 1) for i in range(nx)]
    E_ += [(idx(i, j), idx(i, j + 1)) for j in range(ny) for i in range(nx + 1)]
    E_ = np.array(E_)
    d = X[E_[:, 1]] - X[E_[:, 0]]
    normals = np.cross(d, [0.0, 0.0, 1.0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    fx = np.zeros((len(X), 6), dtype=bool)
    corners = [idx(0, 0), idx(nx, 0), idx(0, ny), idx(nx, ny)]
    fx[corners, :3] = True
    fr = Frame(X, E_, normals, (SEC,), np.zeros(len(E_), dtype=np.int64), E, G, fx)
    return fr, corners


def test_plane_grid_under_uniform_load_matches_pynite_within_one_percent():
    Pynite = pytest.importorskip("Pynite", reason="PyNiteFEA is in the test extra: pip install -e .[test]")
    fr, corners = _grid()
    q = 1.2
    c = case(fr, line=(0, 0, -q))
    sol = run(fr, c)
    m = Pynite.FEModel3D()
    for i, (x, y, z) in enumerate(fr.X):
        m.add_node(f"N{i}", x, y, z)
    m.add_material("steel", E, G, 0.3, 7.85e-9)
    # PyNite's horizontal members have their local z horizontal: their Iy resists vertical bending (strong here)
    m.add_section("plate", SEC.A, SEC.Iy, SEC.Iz, SEC.J)
    for k, (a, b) in enumerate(fr.elements):
        m.add_member(f"M{k}", f"N{a}", f"N{b}", "steel", "plate")
        m.add_member_dist_load(f"M{k}", "FZ", -q, -q)
    for i in corners:
        m.def_support(f"N{i}", True, True, True, False, False, False)
    m.analyze_linear(check_statics=False)
    uz = np.array([m.nodes[f"N{i}"].DZ["Combo 1"] for i in range(fr.n_nodes)])
    ours = sol.displacements["c"][:, 2]
    k = int(np.argmax(np.abs(uz)))
    assert abs(uz[k]) > 1.0  # a real deflection, mm
    assert ours[k] == pytest.approx(uz[k], rel=0.01)
    np.testing.assert_allclose(ours, uz, rtol=0.01, atol=0.01 * abs(uz[k]))
    Mp = np.array([max(abs(m.members[f"M{j}"].max_moment("My", "Combo 1")),
                       abs(m.members[f"M{j}"].min_moment("My", "Combo 1"))) for j in range(fr.n_elements)])
    np.testing.assert_allclose(moments(fr, sol), Mp, rtol=0.01, atol=0.01 * Mp.max())


def _truss(a=2000.0, h=1500.0):
    """A two-panel Warren truss in the x-z plane: bottom nodes 0, 1, 2 (a pin at 0, a roller at 2), top
    nodes 3, 4; every node held out of its plane (y), members pinned at both ends."""
    X = [[0, 0, 0], [2 * a, 0, 0], [4 * a, 0, 0], [a, 0, h], [3 * a, 0, h]]
    members = [[0, 1], [1, 2], [3, 4], [0, 3], [3, 1], [1, 4], [4, 2]]
    fixed = {i: (1,) for i in range(5)}
    fixed[0], fixed[2] = (0, 1, 2), (1, 2)
    return frame(X, members, fixed, pinned=True)


def test_a_pinned_triangulated_truss_carries_the_member_forces_of_the_method_of_joints():
    a, h, P = 2000.0, 1500.0, 30000.0
    fr = _truss(a, h)
    sol = run(fr, case(fr, nodal={1: (0, 0, -P)}))
    F = sol.end_forces["c"]
    N = -F[:, 0]                                   # + tension
    sin = h / np.hypot(a, h)
    expected = [P * a / (2 * h), P * a / (2 * h), -P * a / h,       # bottom chord, top chord
                -P / (2 * sin), P / (2 * sin), P / (2 * sin), -P / (2 * sin)]   # diagonals
    np.testing.assert_allclose(N, expected, rtol=1e-6)
    assert np.abs(F[:, [4, 5, 10, 11]]).max() < 1e-6 * P * a    # no end moments: pinned
    # a line load on the top chord: the member spans simply between its pins, w L^2 / 8 at midspan
    w = 2.0
    line = np.zeros((fr.n_elements, 3))
    line[2] = (0.0, 0.0, -w)
    sol = run(fr, LoadCase("c", np.zeros((fr.n_nodes, 6)), line))
    assert moments(fr, sol)[2] == pytest.approx(w * (2 * a) ** 2 / 8, rel=1e-6)
    assert np.abs(sol.end_forces["c"][:, [4, 5, 10, 11]]).max() < 1e-6 * w * a * a


def test_a_pinned_quad_grid_is_named_a_mechanism_by_counting_its_members():
    fr, _ = _grid()
    import dataclasses

    fr = dataclasses.replace(fr, pinned=True)
    with pytest.raises(MechanismError, match=r"pin-jointed.*mechanism.*31 beams for 48 free node translations"):
        solve(fr, {"c": case(fr, line=(0, 0, -1.0))})


def test_the_section_class_turns_the_moment_to_the_top_fibre():
    """A tee cantilever (the flange on top) under a tip load down: hogging all along, so its stem's free
    tip is compressed (class 4 for a T 200x100x10/12); told that the top is the other way, it would be
    sagging (class 1).  Local y of a beam along x with the normal y points down (OpenSees: y = vecxz x x)."""
    import dataclasses

    from fabricate.structure.results import evaluate
    from fabricate.structure.sections import tee

    T = tee(200.0, 100.0, 10.0, 12.0)
    fr = dataclasses.replace(frame([[0, 0, 0], [L, 0, 0]], [[0, 1]], {0: FIX}), sections=(T,))
    assert fr.local_axes()[0, 1] @ [0, 0, 1] == pytest.approx(-1.0)
    c = case(fr, nodal={1: (0, 0, -1000.0)})
    sol = run(fr, c)
    uls = [("ULS", "uls", {"c": 1.0})]

    def cls(top):
        r = evaluate(dataclasses.replace(fr, top=top), {"c": c}, sol, uls, fy=355.0, deflection_limit=200.0,
                     span_mm=L)
        return r.section_class, r.class_M_kNm[0]

    up, M = cls(np.array([-1.0]))      # local -y is the top: right
    assert up.cls[0] == 4 and up.part[0] == "stem" and M == pytest.approx(-1000.0 * L * 1e-6)  # hogging at the root
    down, M = cls(np.array([1.0]))
    assert down.cls[0] < 4 and M > 0
    unknown, _ = cls(None)             # both signs: the worse
    assert unknown.cls[0] == 4
