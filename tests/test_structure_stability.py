"""Stability: alpha_cr of the linear buckling analysis against Euler's closed forms (within 1 %),
the P-Delta solution against the closed form of a compressed cantilever, and the check's
second-order analysis where alpha_cr < 10.  Units: mm, N, MPa."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from fabricate.structure.engine import solve_second_order
from fabricate.structure.frame import Frame
from fabricate.structure.loads import LoadCase
from fabricate.structure.sections import plate
from fabricate.structure.stability import Assembly

E, G = 210000.0, 81000.0
SEC = plate(60.0, 200.0)
I_MIN = min(SEC.Iy, SEC.Iz)
L = 4000.0
P = 1000.0


def strut(fixed: dict, nel: int = 1, pinned: bool = False, **kw) -> Frame:
    X = np.array([[i * L / nel, 0.0, 0.0] for i in range(nel + 1)])
    fx = np.zeros((nel + 1, 6), dtype=bool)
    for i, dofs in fixed.items():
        fx[i, list(dofs)] = True
    return Frame(X, np.array([[i, i + 1] for i in range(nel)]), np.tile([0.0, 1.0, 0.0], (nel, 1)), (SEC,),
                 np.zeros(nel, dtype=np.int64), E, G, fx, pinned=pinned, **kw)


def alpha_cr(fr: Frame, **kw) -> float:
    asm = Assembly(fr, **kw)
    return asm.buckling(-P * np.ones(len(asm.sub))).alpha_cr


def euler(K: float, I: float = I_MIN) -> float:
    return np.pi ** 2 * E * I / (K * L) ** 2 / P


@pytest.mark.parametrize("pinned", [False, True])
def test_pinned_pinned_strut_buckles_at_the_euler_load(pinned):
    fr = strut({0: (0, 1, 2, 3), 1: (1, 2)}, pinned=pinned)   # torsion held at one end
    assert alpha_cr(fr) == pytest.approx(euler(1.0), rel=0.01)


def test_cantilever_buckles_at_a_quarter_of_the_euler_load():
    fr = strut({0: range(6)})
    assert alpha_cr(fr) == pytest.approx(euler(2.0), rel=0.01)


def test_a_strut_held_sideways_buckles_about_its_strong_axis_in_the_sparse_solver(monkeypatch):
    import fabricate.structure.stability as st

    monkeypatch.setattr(st, "DENSE", 10)     # the sparse (eigsh) path on a small frame
    fr = strut({0: (0, 1, 2, 3), 8: (1, 2)}, nel=8)
    fixed = fr.fixed.copy()
    fixed[:, 1] = True                        # every node held across: weak-axis buckling prevented ...
    fr = dataclasses.replace(fr, fixed=fixed)
    assert alpha_cr(fr, subdivisions=1) == pytest.approx(euler(1.0, SEC.Iy), rel=0.01)   # ... the strong axis


def test_a_stiff_spring_at_the_top_of_a_cantilever_makes_it_a_propped_one():
    springs = np.zeros((2, 6))
    springs[1, 1:3] = 1e9                     # N/mm, both transverse directions at the top
    fr = strut({0: range(6), 1: (3,)}, springs=springs)
    assert alpha_cr(fr) == pytest.approx(euler(0.6992), rel=0.01)   # fixed-pinned: K = 0.699


def test_p_delta_cantilever_matches_the_closed_form_of_a_compressed_cantilever():
    """Tip load H across and P along a cantilever of 16 elements: base moment H tan(kL) / k."""
    nel = 16
    X = np.array([[0.0, 0.0, i * L / nel] for i in range(nel + 1)])
    fx = np.zeros((nel + 1, 6), dtype=bool)
    fx[0] = True
    fr = Frame(X, np.array([[i, i + 1] for i in range(nel)]), np.tile([0.0, 1.0, 0.0], (nel, 1)), (SEC,),
               np.zeros(nel, dtype=np.int64), E, G, fx)
    Pc = 0.4 * np.pi ** 2 * E * I_MIN / (2 * L) ** 2
    H = 1000.0
    nodal = np.zeros((nel + 1, 6))
    nodal[nel, 2] = -Pc
    nodal[nel, 1] = H                         # across the weak axis (global y is the local z here)
    got = solve_second_order(fr, LoadCase("c", nodal, np.zeros((nel, 3))), X)
    assert got is not None
    F, U, R, _ = got
    k = np.sqrt(Pc / (E * I_MIN))
    assert np.hypot(R[0, 3], R[0, 4]) == pytest.approx(H * np.tan(k * L) / k, rel=0.01)
    assert U[nel, 1] == pytest.approx(H * (np.tan(k * L) - k * L) / (Pc * k), rel=0.01)


def test_the_check_solves_second_order_where_alpha_cr_is_below_10():
    from optimize.modelling import shapes

    from fabricate.app.config import parse_config
    from fabricate.cad import PartSpec
    from fabricate.offset import offset_structure
    from fabricate.structure.check import check_structure, report
    from pathlib import Path

    mesh = shapes.revolution(shapes.dome_profile(radius=10.0, rise=4.0, k=7), 12, name="dome")
    dome = offset_structure(mesh.with_vertices(mesh.V * 1000.0), [0.0, -200.0])
    spec = PartSpec(glass_thickness=10.0, beam_width=60.0, beam_depth=200.0)

    def opts(**kw):
        data = {"input": {"shape": {"name": "dome"}},
                "structure": dict(check="report", loads={"snow": 6.0, "temperature": 0.0}, **kw)}
        return parse_config(data, source=Path("t.yaml")).structure.to_options()

    chk = check_structure(dome, opts(), spec)
    rep = report(chk)["stability"]
    assert rep["alpha_cr"] < 10
    low = [k for k, a in rep["alpha_cr_per_combination"].items() if a is not None and a < 10]
    assert low and set(rep["second_order"]) == set(low)
    assert all(v == "P-Delta" for v in rep["second_order"].values())
    assert rep["utilization"] > rep["utilization_first_order"]     # the imperfection and P-Delta add moments
    off = check_structure(dome, opts(stability="off"), spec)
    assert off.stability is None and off.max_utilization == pytest.approx(rep["utilization_first_order"])
