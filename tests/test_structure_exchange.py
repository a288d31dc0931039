"""For the checking engineer (#35 item 8): reactions.csv, member_forces.csv and structure_model.py.

The exported OpenSees script, run by itself in a subprocess, reproduces the CSVs' reactions and member
end forces (1e-6 relative, plus 1e-9 of the file's largest figure for round-off near zero) on a rigid
frame, on support springs with semi-rigid joints, on pinned joints and with every ULS combination solved
second order; the reactions balance the applied loads of every case and combination.
Units in the files: kN, kNm, mm.
"""
from __future__ import annotations

import csv
import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from _pipeline_fixtures import NO_FILES, tiny_config
from fabricate.app.config import parse_config
from fabricate.cad import PartSpec
from fabricate.offset import offset_structure
from fabricate.structure.check import StructureCheck, beam_table, build, check_structure, report, solve_frame
from optimize.modelling import shapes

SPEC = PartSpec(glass_thickness=10.0, beam_width=60.0, beam_depth=200.0)
FORCES = ("Fx_kN", "Fy_kN", "Fz_kN", "Mx_kNm", "My_kNm", "Mz_kNm")
END_FORCES = ("N_kN", "Vy_kN", "Vz_kN", "T_kNm", "My_kNm", "Mz_kNm")
KEYS = ("load", "kind", "analysis", "node", "beam", "end")


def options(**structure):
    data = {"input": {"shape": {"name": "dome"}}, "structure": dict({"check": "report"}, **structure)}
    return parse_config(data, source=Path("t.yaml")).structure.to_options()


@pytest.fixture(scope="module")
def dome():
    mesh = shapes.revolution(shapes.dome_profile(radius=8.0, rise=3.0, k=4), 8, name="dome")
    return offset_structure(mesh.with_vertices(mesh.V * 1000.0), [0.0, -200.0])


@pytest.fixture(scope="module")
def triangulated():
    from optimize.mesh import Mesh

    quads = shapes.revolution(shapes.dome_profile(radius=10.0, rise=4.0, k=4), 8, name="dome")
    tri = np.concatenate([quads.F[:, [0, 1, 2]], quads.F[:, [0, 2, 3]]])
    return offset_structure(Mesh(quads.V * 1000.0, tri), [0.0, -200.0])


def sprung(structure, joint_stiffness: float = 0.0) -> StructureCheck:
    """The dome on springs (the lowest ring: fixed vertically, sprung sideways and about the vertical),
    with semi-rigid joints where ``joint_stiffness`` (N mm/rad) is given, solved as check_structure solves."""
    opts = options()
    frame, supports, cases = build(structure, opts, SPEC)
    fixed = frame.fixed.copy()
    springs = np.zeros((frame.n_nodes, 6))
    springs[supports] = [2e3, 3e3, 5e5, 0.0, 0.0, 1e9]
    fixed[supports, :2] = False   # the springs hold x and y; z stays fixed
    fixed[supports, 2] = True
    frame = replace(frame, fixed=fixed, springs=springs, joint_stiffness=joint_stiffness)
    solution, results, stab = solve_frame(frame, cases, opts, structure)
    return StructureCheck(frame, cases, solution, results, supports, frame.sections[0], opts, {}, stab)


def read(path: Path) -> list[dict]:
    with open(path, newline="", encoding="utf-8") as fh:
        assert fh.readline().startswith("#")   # the units (and axes) line
        return list(csv.DictReader(fh))


def written(check, folder: Path) -> Path:
    from fabricate.structure.exchange import write_exchange

    files = write_exchange(check, folder, "test dome")
    assert set(files) == {"reactions.csv", "member_forces.csv", "structure_model.py"}
    return folder


def run_script(folder: Path, out: Path) -> None:
    out.mkdir()
    proc = subprocess.run([sys.executable, str(folder / "structure_model.py"), str(out)], capture_output=True,
                          text=True, timeout=300, cwd=out)
    assert proc.returncode == 0, proc.stderr[-2000:]


def agree(ours: list[dict], theirs: list[dict], columns) -> None:
    assert len(ours) == len(theirs) > 0
    keys = [c for c in KEYS if c in ours[0]]
    assert [[r[c] for c in keys] for r in ours] == [[r[c] for c in keys] for r in theirs]
    a = np.array([[float(r[c]) for c in columns] for r in ours])
    b = np.array([[float(r[c]) for c in columns] for r in theirs])
    np.testing.assert_allclose(b, a, rtol=1e-6, atol=1e-9 * np.abs(a).max())


def check_of(kind, dome, triangulated):
    if kind == "rigid":
        return check_structure(dome, options(), SPEC)
    if kind == "springs":
        return sprung(dome)
    if kind == "springs, semi-rigid":
        return sprung(dome, 5e9)
    if kind == "pinned":
        return check_structure(triangulated, options(connections="pinned"), SPEC)
    return check_structure(dome, options(stability="always"), SPEC)


@pytest.mark.parametrize("kind", ["rigid", "springs", "springs, semi-rigid", "pinned", "second order"])
def test_the_exported_opensees_script_reproduces_the_reactions_and_member_end_forces(tmp_path, dome, triangulated,
                                                                                      kind):
    chk = check_of(kind, dome, triangulated)
    if kind == "second order":
        assert "P-Delta" in chk.stability.second_order.values()
    folder = written(chk, tmp_path)
    run_script(folder, tmp_path / "theirs")
    ours, theirs = read(folder / "reactions.csv"), read(tmp_path / "theirs" / "structure_model_reactions.csv")
    agree(ours, theirs, ("x_mm", "y_mm", "z_mm") + FORCES)
    agree(read(folder / "member_forces.csv"), read(tmp_path / "theirs" / "structure_model_member_forces.csv"),
          END_FORCES)
    analyses = {r["load"]: r["analysis"] for r in ours}
    assert all(analyses[k] == v for k, v in (chk.stability.second_order if chk.stability else {}).items())


def totals(chk) -> dict[str, np.ndarray]:
    """{load: (3,) applied force, kN} of every case and combination (from the check's load cases; a
    combination solved P-Delta carries its line loads over the beams of its imperfect geometry)."""
    from fabricate.structure.loads import combine

    fr = chk.frame
    geometry = chk.stability.geometry if chk.stability is not None else {}
    out = {name: c.total_force(fr.lengths()) * 1e-3 for name, c in chk.cases.items()}
    for name, _, factors in chk.options.combination_list():
        if name in geometry:
            X = geometry[name]
            L = np.linalg.norm(X[fr.elements[:, 1]] - X[fr.elements[:, 0]], axis=1)
            out[name] = combine(chk.cases, factors, name).total_force(L) * 1e-3
        else:
            out[name] = sum(f * out[c] for c, f in factors.items())
    return out


SEMI_RIGID_REACTIONS = pytest.mark.xfail(strict=True, reason=(
    "engine: with semi-rigid joints the members reach a node through equalDOF (Transformation handler) and "
    "OpenSees' nodeReaction leaves those forces out: a support's reaction is its springs' force only"))


@pytest.mark.parametrize("kind", ["rigid", "springs", "second order",
                                  pytest.param("springs, semi-rigid", marks=SEMI_RIGID_REACTIONS)])
def test_the_reactions_balance_the_applied_loads_of_every_case_and_combination(tmp_path, dome, triangulated, kind):
    chk = check_of(kind, dome, triangulated)
    rows = read(written(chk, tmp_path) / "reactions.csv")
    loads = totals(chk)
    assert {r["load"] for r in rows} == set(loads)
    sup = np.nonzero(chk.frame.supported())[0]
    for name, applied in loads.items():
        mine = [r for r in rows if r["load"] == name]
        assert [r["node"] for r in mine] == [chk.frame.node_ids[i] for i in sup]   # one row per support
        np.testing.assert_allclose([[float(r[c]) for c in ("x_mm", "y_mm", "z_mm")] for r in mine], chk.frame.X[sup],
                                   rtol=1e-9, atol=1e-6)
        total = np.array([[float(r[c]) for c in FORCES[:3]] for r in mine]).sum(axis=0)
        size = max(float(np.linalg.norm(applied)), float(np.abs(chk.cases[name].nodal).sum() * 1e-3)
                   if name in chk.cases else 0.0, 1e-9)
        assert np.linalg.norm(total + applied) <= 1e-6 * size, (name, total, applied)


def test_member_forces_have_both_ends_of_every_beam_and_mark_the_governing_combinations(tmp_path, dome):
    chk = check_structure(dome, options(), SPEC)
    rows = read(written(chk, tmp_path) / "member_forces.csv")
    fr, rep = chk.frame, report(chk)
    case = [r for r in rows if r["load"] == "glass"]
    assert [(r["beam"], r["end"]) for r in case] == [(b, e) for b in fr.ids for e in "ij"]
    assert [r["node"] for r in case] == [fr.node_ids[i] for i in fr.elements.reshape(-1)]
    # each beam in equilibrium along its axis: N_i + N_j + w_x L = 0 (local axes, kN)
    F = np.array([[float(r[c]) for c in END_FORCES] for r in case]).reshape(-1, 12)
    wx = chk.solution.line_local["glass"][:, 0] * fr.lengths() * 1e-3
    np.testing.assert_allclose(F[:, 0] + F[:, 6] + wx, 0.0, atol=1e-6 * np.abs(F[:, 0]).max())
    frame_uls = {r["load"] for r in rows if "frame ULS" in r["governs"]}
    assert frame_uls == {rep["governing_combination"]}
    assert {r["load"] for r in rows if "frame SLS" in r["governs"]} == {chk.results.governing_sls}
    table = {b["id"]: b["combination"] for b in beam_table(chk)}
    assert all(table[r["beam"]] == r["load"] for r in rows if "beam utilization" in r["governs"])
    assert {r["beam"] for r in rows if "beam utilization" in r["governs"]} == set(fr.ids)
    reac = read(tmp_path / "reactions.csv")
    marked = [r for r in reac if "node max F" in r["governs"]]
    assert sorted(r["node"] for r in marked) == sorted({r["node"] for r in reac})   # one per support node


def test_a_run_writes_the_reactions_member_forces_and_model_script_and_lists_them(tmp_path):
    from fabricate.app.pipeline import run_pipeline

    cfg = tiny_config(tmp_path, "ex", outputs=dict(NO_FILES, bom=True),
                      structure={"check": "report", "supports": "boundary", "glass": {"check": "off"}})
    summary = run_pipeline(cfg, tmp_path / "out")
    assert summary.exit_code == 0, summary.message
    out = tmp_path / "out" / "ex"
    rep = json.loads((out / "report.json").read_text())
    for name in ("reactions.csv", "member_forces.csv", "structure_model.py"):
        assert (out / name).stat().st_size > 0 and name in rep["files"]
    beams = {r["beam"] for r in read(out / "member_forces.csv")}
    assert beams == {b["id"] for b in rep["structure"]["beams"]}
    nodes = {r["node"] for r in read(out / "reactions.csv")}
    assert len(nodes) == rep["structure"]["supports"]["count"]


def test_with_semi_rigid_joints_a_case_solved_with_others_is_the_case_solved_alone(dome):
    """Every case of a semi-rigid frame is solved from zero (engine.FRESH_MODEL): one step after another on the
    same model drifted (the second case 6 % off on this dome on springs)."""
    from fabricate.structure.engine import solve

    chk = sprung(dome, 5e9)
    together = solve(chk.frame, {k: chk.cases[k] for k in ("self_weight", "glass", "snow")})
    for name in ("glass", "snow"):
        alone = solve(chk.frame, {name: chk.cases[name]})
        U = alone.displacements[name]
        np.testing.assert_allclose(together.displacements[name], U, rtol=1e-9, atol=1e-9 * np.abs(U).max())
