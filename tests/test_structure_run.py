"""The structural check on a real offset structure, in a run and on the command line.

A dome of revolution (10 m, 16 x 7 quads: conical by construction) offset 200 mm: every solved
model balances, loads scale results linearly, the panel loads arrive whole on the beams, sizing
returns a lighter section that passes (by a full solve), and bad input is exit 2 naming the key.
"""
from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from _pipeline_fixtures import NO_FILES, REPO, tiny_config
from fabricate.cad import PartSpec
from fabricate.app.config import parse_config
from fabricate.offset import offset_structure
from fabricate.structure.check import beam_table, check_structure, report
from fabricate.structure.loads import panel_area_vectors
from fabricate.structure.sizing import size_sections
from optimize.modelling import shapes


@pytest.fixture(scope="module")
def dome():
    mesh = shapes.revolution(shapes.dome_profile(radius=10.0, rise=4.0, k=7), 16, name="dome")
    return offset_structure(mesh.with_vertices(mesh.V * 1000.0), [0.0, -200.0])


def options(**structure):
    data = {"input": {"shape": {"name": "dome"}}, "structure": dict({"check": "report"}, **structure)}
    return parse_config(data, source=Path("t.yaml")).structure.to_options()


SPEC = PartSpec(glass_thickness=10.0, beam_width=60.0, beam_depth=200.0)


def test_every_case_balances_and_the_panel_loads_arrive_whole(dome):
    chk = check_structure(dome, options(), SPEC)
    eq = chk.results.equilibrium
    assert set(eq) >= {"self_weight", "glass", "snow", "wind_pressure", "wind_suction"}
    assert max(eq.values()) < 1e-6
    area = np.linalg.norm(panel_area_vectors(dome.mesh), axis=1).sum()  # mm2
    glass = chk.cases["glass"].total_force(chk.frame.lengths())
    assert -glass[2] == pytest.approx(25.0e-6 * 10.0 * area, rel=1e-9)   # 25 kN/m3 x 10 mm x area
    snow = chk.cases["snow"].total_force(chk.frame.lengths())
    plan = np.abs(panel_area_vectors(dome.mesh)[:, 2]).sum()
    assert -snow[2] == pytest.approx(0.8e-3 * plan, rel=1e-9)
    steel = chk.cases["self_weight"].total_force(chk.frame.lengths())
    assert -steel[2] == pytest.approx(78.5e-6 * 60 * 200 * chk.frame.lengths().sum(), rel=1e-9)
    rep = report(chk)
    assert rep["equilibrium"]["max"] < 1e-6
    assert rep["governing_combination"] in rep["utilization"]["worst"][0]["combination"]
    assert rep["supports"]["count"] == 16  # the lowest ring


def test_loads_that_scale_linearly_scale_utilization_and_deflection_linearly(dome):
    base = dict(steel_unit_weight=78.5, glass_unit_weight=25.0, finishes=0.2, snow=0.8, wind_pressure=0.5,
                wind_suction=0.4, maintenance=0.4, temperature=30.0)
    one = check_structure(dome, options(loads=base, stability="off"), SPEC)   # first order: linear
    two = check_structure(dome, options(loads={k: 2 * v for k, v in base.items()}, stability="off"), SPEC)
    np.testing.assert_allclose(two.results.utilization, 2 * one.results.utilization, rtol=1e-7)
    np.testing.assert_allclose(two.results.deflection_mm, 2 * one.results.deflection_mm, rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(two.results.displacement_mm, 2 * one.results.displacement_mm, rtol=1e-7)
    assert max(two.results.equilibrium.values()) < 1e-6


def test_sizing_picks_a_lighter_section_that_passes_by_a_full_solve(dome):
    cands = [{"shape": "plate", "depth": 200, "width": 1}, {"shape": "plate", "depth": 200, "width": 8},
             {"shape": "rhs", "depth": 200, "width": 60, "web": 4}, {"shape": "plate", "depth": 200, "width": 30}]
    # no temperature: the ring beams between pinned supports, held, would buckle under E A alpha dT
    opt = options(sizing={"sections": cands, "group_by": "boundary"}, loads={"temperature": 0.0})
    sz = size_sections(dome, opt, SPEC)
    assert sz.passes and sz.check.passes()
    assert sz.sized_mass_kg < sz.configured_mass_kg and sz.saved_kg > 0
    assert "plate 1x200" not in sz.chosen.values()  # far too weak: never chosen
    final = check_structure(dome, opt, SPEC, sections=sz.check.frame.sections, section_of=sz.check.frame.section_of)
    assert final.max_utilization == pytest.approx(sz.check.max_utilization, rel=1e-9)


def test_a_support_that_does_not_exist_names_the_key(dome):
    from optimize.errors import ConfigError

    with pytest.raises(ConfigError, match=r"structure\.supports: vertex 100000 does not exist"):
        check_structure(dome, options(supports=[3, 100000]), SPEC)


def test_a_frame_on_pinned_joints_is_a_mechanism_naming_the_key(dome):
    from fabricate.structure.engine import MechanismError

    with pytest.raises(MechanismError, match=r"structure\.connections = 'pinned'"):
        check_structure(dome, options(connections="pinned"), SPEC)


def test_a_triangulated_dome_on_pinned_joints_solves_and_its_members_span_simply():
    from optimize.mesh import Mesh

    quads = shapes.revolution(shapes.dome_profile(radius=10.0, rise=4.0, k=4), 8, name="dome")
    tri = np.concatenate([quads.F[:, [0, 1, 2]], quads.F[:, [0, 2, 3]]])
    s = offset_structure(Mesh(quads.V * 1000.0, tri), [0.0, -200.0])
    chk = check_structure(s, options(connections="pinned"), SPEC)
    assert max(chk.results.equilibrium.values()) < 1e-6
    F, w = chk.solution.end_forces["glass"], chk.solution.line_local["glass"]
    L = chk.frame.lengths()
    scale = float((np.abs(w).max(axis=1) * L ** 2).max())
    assert np.abs(F[:, [4, 5, 10, 11]]).max() < 1e-6 * scale         # no moment at a pinned end
    from fabricate.structure.results import internal_forces

    _, _, Ms, _, _ = internal_forces(F, w, L)
    np.testing.assert_allclose(np.abs(Ms).max(axis=1), np.abs(w[:, 1]) * L ** 2 / 8, rtol=1e-6,
                               atol=1e-9 * scale)                     # each member: w L^2 / 8
    assert report(chk)["connections"] == "pinned"


def test_the_frame_knows_which_side_of_each_beam_the_glass_is(dome):
    from fabricate.structure.frame import frame_from_offset
    from fabricate.structure.sections import tee

    assert dome.layer_mesh(1).V[:, 2].mean() < dome.layer_mesh(0).V[:, 2].mean()   # the beams hang below
    fr, _ = frame_from_offset(dome, tee(200, 100, 10, 12), E=210000.0, G=81000.0)
    toward_glass = fr.local_axes()[:, 1] * fr.top[:, None]
    assert (toward_glass[:, 2] > 0.5).all()                                          # up, on a dome


def test_the_report_lists_the_beams_whose_section_is_class_4(dome):
    thin = {"shape": "tee", "depth": 200, "width": 100, "web": 4, "flange": 12}   # stem c/t = 47
    chk = check_structure(dome, options(section=thin), SPEC)
    rep = report(chk)
    c4 = rep["class_4"]
    assert c4["count"] == chk.frame.n_elements and len(c4["beams"]) == c4["count"] and not rep["pass"]
    w = c4["worst"][0]
    assert w["part"] == "stem" and w["c_t"] == pytest.approx(47.0) and w["ratio"] > 1 and w["id"] in c4["beams"]
    from fabricate.structure.outputs import html_section, structure_measures

    assert "class 4" in html_section(dict(rep, notes=[])) and w["id"] in html_section(dict(rep, notes=[]))
    m = structure_measures(chk)["structure_section_class"]
    assert m["pass"] is False and m["max"] == pytest.approx(w["ratio"], rel=1e-4) and m["enforced"] is False
    thick = {"shape": "rhs", "depth": 200, "width": 100, "web": 8}                   # web c/t = 22: class 1
    ok = check_structure(dome, options(section=thick), SPEC)
    assert report(ok)["class_4"]["count"] == 0 and {b["class"] for b in beam_table(ok)} <= {1, 2, 3}


def test_a_run_writes_the_structure_table_columns_and_pictures(tmp_path):
    from fabricate.app.pipeline import run_pipeline

    outs = dict(NO_FILES, bom=True, pictures=True)
    cfg = tiny_config(tmp_path, "st", outputs=outs, structure={"check": "report", "supports": "boundary"})
    summary = run_pipeline(cfg, tmp_path / "out")
    assert summary.exit_code == 0, summary.message
    out = tmp_path / "out" / "st"
    import json

    rep = json.loads((out / "report.json").read_text())
    s = rep["structure"]
    assert s["equilibrium"]["max"] < 1e-6 and len(s["beams"]) == s["elements"]
    assert rep["measures"]["structure_utilization"]["max"] == pytest.approx(s["utilization"]["max"])
    assert (out / "structure_utilization.png").stat().st_size > 1000
    assert "structure_deflection.png" in rep["pictures"]
    rows = list(csv.DictReader((out / "bom.csv").open()))
    beams = [r for r in rows if r["kind"] == "beam"]
    assert beams and all(r["utilization"] and r["section"] for r in beams)
    assert all(r["utilization"] == "" for r in rows if r["kind"] != "beam")
    assert max(float(r["utilization"]) for r in beams) == pytest.approx(s["utilization"]["max"], abs=1e-4)


def test_enforce_with_a_section_far_too_small_is_exit_3(tmp_path):
    from fabricate.app.pipeline import run_pipeline

    cfg = tiny_config(tmp_path, "weak", structure={"check": "enforce", "supports": "boundary",
                                                   "section": {"shape": "plate", "depth": 200, "width": 0.5}})
    summary = run_pipeline(cfg, tmp_path / "out")
    assert summary.exit_code == 3 and "structure_utilization" in summary.failed


def test_enforce_fails_a_class_4_section_with_exit_3(tmp_path):
    from fabricate.app.pipeline import run_pipeline

    # strong enough (utilization about 0.4), but the stem (c/t 36) is class 4 wherever it is compressed
    thin = {"shape": "tee", "depth": 200, "width": 200, "web": 5, "flange": 20}
    # no temperature: the held ring beams would fail on it too (this test is about the class)
    cfg = tiny_config(tmp_path, "thin", structure={"check": "enforce", "supports": "boundary", "section": thin,
                                                   "loads": {"temperature": 0.0}})
    summary = run_pipeline(cfg, tmp_path / "out")
    assert summary.exit_code == 3 and summary.failed == ["structure_section_class"]
    assert "every requirement met" not in summary.message and "structure_section_class" in summary.message


def test_the_bom_rows_of_welded_beams_carry_their_beams_figures(tmp_path):
    from fabricate.app.pipeline import run_pipeline

    tee = {"section": "tee", "web_mm": 10, "flange_mm": 12, "flange_width_mm": 100}
    cfg = tiny_config(tmp_path, "tee", outputs=dict(NO_FILES, bom=True), parts={"beam": tee},
                      structure={"check": "report", "supports": "boundary"})
    summary = run_pipeline(cfg, tmp_path / "out")
    assert summary.exit_code == 0, summary.message
    rows = [r for r in csv.DictReader((tmp_path / "out" / "tee" / "bom.csv").open()) if r["kind"] == "beam"]
    assert rows and rows[0]["id"] == "B0001.1"          # one row per plate, "unit" the beam
    assert all(r["section"].startswith("tee ") and r["utilization"] for r in rows)
    by_unit = {}
    for r in rows:
        by_unit.setdefault(r["unit"], set()).add((r["section"], r["N_kN"], r["utilization"]))
    assert all(len(v) == 1 for v in by_unit.values())   # every plate of a beam states that beam's figures
    import json

    s = json.loads((tmp_path / "out" / "tee" / "report.json").read_text())["structure"]
    assert max(float(r["utilization"]) for r in rows) == pytest.approx(s["utilization"]["max"], abs=1e-4)


def _cli(tmp_path, *sets):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("input:\n  shape:\n    name: dome\n    params: {radius: 5000, rise: 2000, meridians: 6, rings: 3}\n"
                   "outputs: {step: false, stl: false, 3mf: false, dxf: false, svg: false, bom: false, "
                   "pictures: false, html: false}\nstructure:\n  check: report\n")
    args = [sys.executable, "-m", "fabricate", "run", str(cfg), "--out", str(tmp_path / "o"), "-q"]
    for s in sets:
        args += ["--set", s]
    return subprocess.run(args, cwd=REPO, capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("setting, key", [
    ("structure.loads.snow=-0.5", "structure.loads.snow"),
    ("structure.supports=[]", "structure.supports"),
    ("structure.connections=pinned", "structure.connections"),
])
def test_bad_structure_input_is_exit_2_with_one_line_naming_the_key(tmp_path, setting, key):
    proc = _cli(tmp_path, setting)
    assert proc.returncode == 2, proc.stderr
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and key in lines[0] and "Traceback" not in proc.stderr
    assert not (tmp_path / "o" / "c").exists()


def test_reference_config_lists_every_structure_key():
    import yaml

    from fabricate.app.config_structure import LoadsOption, SizingOption, StructureSection

    data = yaml.safe_load((REPO / "configs" / "reference.yaml").read_text())["structure"]
    assert set(data) == set(StructureSection.allowed_keys())
    assert set(data["loads"]) == set(LoadsOption.allowed_keys())
    assert set(data["sizing"]) == set(SizingOption.allowed_keys())
    from fabricate.app.config import load_config

    assert load_config(REPO / "configs" / "reference.yaml").structure.check == "off"  # YAML's bare off


def test_supports_outline_is_the_longest_boundary_loop_and_a_closed_mesh_has_none():
    from fabricate.structure.frame import support_vertices
    from optimize.errors import ConfigError

    ring = shapes.grid(6, 6, size=(5.0, 5.0))  # one boundary loop of 20 vertices
    t = ring.topology
    sel = support_vertices(ring.V, t.is_boundary_vertex, "outline", None, (0, 0, 1), loops=t.boundary_loops)
    assert sorted(sel.tolist()) == sorted(np.nonzero(t.is_boundary_vertex)[0].tolist())
    with pytest.raises(ConfigError, match="structure.supports = 'outline'"):
        support_vertices(ring.V, np.zeros(len(ring.V), bool), "outline", None, (0, 0, 1), loops=[])


def test_fabricate_size_reports_the_lightest_passing_section_and_the_steel_saved(tmp_path):
    cfg = tmp_path / "s.yaml"
    cfg.write_text("input:\n  shape:\n    name: dome\n    params: {radius: 5000, rise: 2000, meridians: 6, rings: 3}\n"
                   "structure:\n  loads: {temperature: 0}\n  sizing:\n    group_by: all\n    sections:\n"
                   "      - {shape: plate, depth: 200, width: 1}\n      - {shape: rhs, depth: 200, width: 60, web: 4}\n"
                   "      - {shape: rhs, depth: 200, width: 60, web: 6}\n"
                   "      - {shape: plate, depth: 200, width: 60}\n")
    proc = subprocess.run([sys.executable, "-m", "fabricate", "size", str(cfg), "--json", str(tmp_path / "s.json")],
                          cwd=REPO, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    import json

    d = json.loads((tmp_path / "s.json").read_text())
    # rhs 200x60x4 is lighter and strong enough, but its webs (c/t 47) are class 4 under the beams' N + M
    assert d["chosen"] == {"all": "rhs 200x60x6"} and d["passes"]
    assert "rhs 200x60x4" in d["class_4_under_the_final_forces"]
    assert d["configured_section"] == "plate 60x200" and d["saved_kg"] > 0
    assert "rhs 200x60x6" in proc.stdout and "saved" in proc.stdout


def test_a_run_with_the_structure_check_checks_every_panel_as_glass(tmp_path):
    """#35 item 7 wired: structure.glass (check: report by default) writes glass_check.csv, the report's
    structure.glass and the measures glass_stress / glass_deflection; off leaves them out."""
    from fabricate.app.pipeline import run_pipeline

    cfg = tiny_config(tmp_path, "gl", outputs=dict(NO_FILES, bom=True),
                      structure={"check": "report", "supports": "boundary", "loads": {"temperature": 0.0}})
    summary = run_pipeline(cfg, tmp_path / "out")
    out = tmp_path / "out" / "gl"
    rep = json.loads((out / "report.json").read_text())
    rows = list(csv.DictReader((out / "glass_check.csv").open()))
    assert summary.exit_code == 0, summary.message
    assert len(rows) == rep["parts"]["panels"]["count"] == 12 and all(0 < float(r["utilization"]) for r in rows)
    assert rep["measures"]["glass_stress"]["max"] == pytest.approx(max(float(r["utilization_stress"]) for r in rows),
                                                                   rel=1e-3)
    assert "glass" in rep["structure"] and rep["measures"]["glass_deflection"]["role"] == "information"
    off = tiny_config(tmp_path, "gl_off", outputs=dict(NO_FILES, bom=True),
                      structure={"check": "report", "supports": "boundary", "loads": {"temperature": 0.0},
                                 "glass": {"check": "off"}})
    run_pipeline(off, tmp_path / "out")
    assert not (tmp_path / "out" / "gl_off" / "glass_check.csv").exists()
