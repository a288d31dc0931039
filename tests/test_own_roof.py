"""A user's own roof (#30): converged work is never lost, how far the design moved is in every
headline, and a limit in mm on it is a requirement when asked for."""
from __future__ import annotations

import json

import pytest

from _pipeline_fixtures import tiny_config
from fabricate.app.pipeline import moved_sentence, outcome, run_pipeline

MESH_ONLY = {"step": False, "stl": False, "3mf": False, "dxf": False, "svg": False, "bom": False,
             "pictures": False, "html": False, "glass_order": False}


def test_a_converged_mesh_whose_parts_cannot_be_built_is_written_and_ends_3(tmp_path, monkeypatch):
    """The CAD stage refuses a converged mesh (a tee web folds at one node): the optimized mesh, the
    layers and the report are written with the reason, marked, exit 3 (it used to end 2 with nothing)."""
    import fabricate.cad as cad
    from fabricate.cad.errors import PartError

    def folds(structure, spec):
        raise PartError("beam B0012 (edge 11): the tee web folds at node N0004; reduce parts.beam_depth",
                        "B0012", 11)

    monkeypatch.setattr(cad, "build_parts", folds)
    summary = run_pipeline(tiny_config(tmp_path, "refused", outputs=dict(MESH_ONLY, step=True)), tmp_path / "out")
    out = tmp_path / "out" / "refused"
    assert (summary.status, summary.exit_code) == ("tolerance_not_reached", 3)
    assert "no panels or beams built from the optimized mesh" in summary.message and "B0012" in summary.message
    assert "reduce parts.beam_depth" in summary.message
    assert (out / "mesh.obj").is_file() and (out / "layer_1.obj").is_file()
    assert (out / "TOLERANCE_NOT_REACHED.txt").is_file() and not (out / "model.step").exists()
    report = json.loads((out / "report.json").read_text())
    assert report["exit_code"] == 3 and "B0012" in report["message"]
    assert report["optimization"]["status"] == "converged"


def test_every_headline_says_how_far_the_design_moved(tmp_path):
    summary = run_pipeline(tiny_config(tmp_path, "moved", outputs=MESH_ONLY), tmp_path / "out")
    report = json.loads((tmp_path / "out" / "moved" / "report.json").read_text())
    close, rough = report["measures"]["closeness"], report["measures"]["roughness"]
    assert close["max_mm"] == pytest.approx(close["max"] * close["diagonal_mm"])
    assert close["max_mm"] > 0 and rough["input"] > 0 and rough["result"] > 0
    assert rough["max"] == pytest.approx((rough["result"] + 0.01) / (rough["input"] + 0.01))
    said = f"design moved up to {close['max_mm']:,.1f} mm ({100 * close['max']:.2f} % of the bounding-box diagonal)"
    assert said in summary.message and said in report["message"]
    assert f"{rough['max']:.2g} x the input's roughness" in summary.message
    named = [(w, k) for m in report["measures"].values() for w in m.get("worst") or ()
             for k in ("face", "beam", "vertex") if k in w]
    assert {k for _, k in named} == {"face", "beam", "vertex"}  # the measures name parts by their file ids
    assert all(w["id"] == f"{dict(face='P', beam='B', vertex='N')[k]}{w[k] + 1:04d}" for w, k in named)


def test_a_limit_in_mm_on_how_far_the_design_moves_is_a_requirement(tmp_path):
    free = run_pipeline(tiny_config(tmp_path, "free", outputs=MESH_ONLY), tmp_path / "out")
    moved = json.loads((tmp_path / "out" / "free" / "report.json").read_text())["measures"]["closeness"]["max_mm"]
    assert free.exit_code == 0 and moved > 1.0
    tight = run_pipeline(tiny_config(tmp_path, "tight", outputs=MESH_ONLY, tolerances={"closeness_mm": moved / 2}),
                         tmp_path / "out")
    assert (tight.status, tight.exit_code) == ("tolerance_not_reached", 3) and "closeness" in tight.failed
    assert f"closeness {moved:,.1f} mm > {moved / 2:g} mm" in tight.message
    loose = run_pipeline(tiny_config(tmp_path, "loose", outputs=MESH_ONLY, tolerances={"closeness_mm": moved * 2}),
                         tmp_path / "out")
    assert loose.exit_code == 0
    report = json.loads((tmp_path / "out" / "loose" / "report.json").read_text())
    assert report["measures"]["closeness"]["role"] == "requirement"
    assert report["measures"]["closeness"]["tolerance_mm"] == pytest.approx(moved * 2)


def test_a_rougher_result_than_the_roughness_tolerance_is_a_warning_not_ok_silently():
    measures = {"planarity": {"enforced": True, "pass": True, "max": 0.0, "tolerance": 1e-6},
                "roughness": {"enforced": False, "pass": False, "max": 3.2, "tolerance": 2.0, "unit": "ratio"},
                "closeness": {"enforced": False, "pass": True, "max": 0.004, "max_mm": 120.0, "tolerance": 0.005}}
    out = outcome(measures)
    assert out.exit_code == 0 and "1 warning(s): roughness 3.2 ratio" in out.message
    assert out.message.endswith("design moved up to 120.0 mm (0.40 % of the bounding-box diagonal), "
                                "3.2 x the input's roughness")
    assert moved_sentence({}) == ""


def test_a_design_of_straight_lines_has_a_finite_roughness_ratio_and_a_report():
    """A hyperbolic paraboloid's rulings are exactly straight and evenly spaced (roughness 0): the ratio
    stays finite (it was inf, written as null, and the report's warnings then raised TypeError)."""
    from fabricate.report.measures import roughness_ratio, warnings

    assert roughness_ratio(0.0, 0.0) == 1.0 and roughness_ratio(0.0, 0.03) == pytest.approx(4.0)
    assert roughness_ratio(0.2, 0.2) == 1.0
    lines = warnings({"roughness": {"enforced": False, "pass": False, "max": None, "tolerance": 2.0, "unit": "ratio"}})
    assert lines == ["roughness nan ratio (max nan ratio > tolerance 2)"]


@pytest.mark.parametrize("connection", ["hub", "none", "mitre"])
def test_the_advice_for_a_short_beam_never_names_what_is_set_and_gives_the_sizes(connection):
    from fabricate.cad.diagnose import beam_hint

    hint = beam_hint(0.0, 60.0, 1.0, 200.0, length_mm=242.0, setback_mm=80.0 if connection == "hub" else 0.0,
                     connection=connection)
    assert "242 mm" in hint
    assert ("parts.node.connection: mitre" in hint) == (connection != "mitre")
    assert ("parts.node.connection: hub" in hint) == (connection == "mitre")
    if connection == "hub":
        assert "stand 80 mm off each node axis" in hint and "to below 109 mm" in hint


REPO = __import__("pathlib").Path(__file__).resolve().parents[1]
NO_CAD_FILES = {f"outputs.{k}": v for k, v in MESH_ONLY.items()}


def test_the_shipped_rhino_roof_in_metres_builds_and_warns_how_far_it_moved(tmp_path):
    """configs/own_roof.yaml: a quad roof nobody here made (COMPAS, MIT), just input and units."""
    from fabricate.app.config import load_config

    cfg = load_config(REPO / "configs" / "own_roof.yaml", overrides=NO_CAD_FILES)
    summary = run_pipeline(cfg, tmp_path / "out")
    assert (summary.status, summary.exit_code) == ("ok", 0)
    report = json.loads((tmp_path / "out" / "own_roof" / "report.json").read_text())
    close = report["measures"]["closeness"]
    assert report["input"]["mm_per_unit"] == 1000.0 and 7000 < close["diagonal_mm"] < 7600
    assert "warning(s): closeness" in summary.message and "design moved up to" in summary.message
    assert close["pass"] is False and close["role"] == "information" and close["max_mm"] > 50
    assert summary.decision.startswith("Route: conical by own lines")
    assert report["measures"]["planarity"]["max"] <= 1e-6 and report["measures"]["folded"]["max"] == 0


def test_the_shipped_tube_shell_that_cannot_be_built_says_why_and_keeps_the_mesh(tmp_path):
    from fabricate.app.config import load_config

    cfg = load_config(REPO / "configs" / "own_roof_tube.yaml", overrides=NO_CAD_FILES)
    summary = run_pipeline(cfg, tmp_path / "out")
    out = tmp_path / "out" / "own_roof_tube"
    assert (summary.status, summary.exit_code) == ("tolerance_not_reached", 3)
    # 200 mm deep beams on a shell this tightly curved: the offset faces turn over (or the beams fold), named
    assert "no panels or beams built" in summary.message and "design moved up to" in summary.message
    assert "mm" in summary.message.split("no panels or beams built", 1)[1]
    assert (out / "mesh.obj").is_file() and (out / "TOLERANCE_NOT_REACHED.txt").is_file()
    # the default 200 mm beams do not fit this shell: a depth that does is taken, said, and is the config as run
    import re

    said = re.search(r"Beams (\d+) mm deep \(parts.beam_depth\): the default 200 mm does not fit", summary.decision)
    assert said, summary.decision
    report = json.loads((out / "report.json").read_text())
    assert report["config"]["parts"]["beam_depth"] == float(said.group(1)) < 200
    assert report["offset"]["distances_mm"] == [0.0, -float(said.group(1))]
    assert said.group(0) in " ".join(report["notes"])


def test_a_beam_depth_the_user_gives_is_honoured_and_the_run_says_what_fits(tmp_path):
    from fabricate.app.config import load_config

    cfg = load_config(REPO / "configs" / "own_roof_tube.yaml", overrides={**NO_CAD_FILES, "parts.beam_depth": 200})
    summary = run_pipeline(cfg, tmp_path / "out")
    assert (summary.status, summary.exit_code) == ("tolerance_not_reached", 3)
    assert "mm deep (parts.beam_depth)" not in summary.decision
    report = json.loads((tmp_path / "out" / "own_roof_tube" / "report.json").read_text())
    assert report["config"]["parts"]["beam_depth"] == 200
    assert "FACES TURN OVER" in summary.message and "The layers come from parts.beam_depth = 200 mm: at most" in summary.message


def test_a_roof_in_a_unit_float64_cannot_hold_to_the_cad_tolerance_is_refused_up_front(tmp_path):
    """A mesh given in metres but saved in micrometres-of-kilometres (coordinates 1e15 mm): one line,
    bad input (exit 2) before the optimizer runs, nothing written (it ended exit 3 after optimizing)."""
    from optimize.errors import MeshError

    mesh = tmp_path / "far.obj"
    mesh.write_text("".join(f"v {x * 1e12} {y * 1e12} {0.1 * x * y * 1e12}\n" for y in range(3) for x in range(3))
                    + "".join(f"f {1 + x + 3 * y} {2 + x + 3 * y} {5 + x + 3 * y} {4 + x + 3 * y}\n"
                              for y in range(2) for x in range(2)))
    cfg = tiny_config(tmp_path, "far", outputs=MESH_ONLY, input={"mesh": str(mesh)}, units="m")
    with pytest.raises(MeshError, match=r"far\.obj: coordinates up to .* the CAD tolerance") as err:
        run_pipeline(cfg, tmp_path / "out")
    assert err.value.exit_code == 2 and "\n" not in str(err.value)
    assert not (tmp_path / "out" / "far").exists()


def test_every_report_counts_degenerate_faces_as_a_requirement(tmp_path):
    run_pipeline(tiny_config(tmp_path, "degen", outputs=MESH_ONLY), tmp_path / "out")
    m = json.loads((tmp_path / "out" / "degen" / "report.json").read_text())["measures"]["degenerate"]
    assert m["role"] == "requirement" and m["pass"] is True and m["max"] == 0
    assert m["shrunk_edges"] == 0 and m["straight_corners"] == 0
    out = outcome({"degenerate": dict(m, max=2.0, **{"pass": False}, tolerance=0)})
    assert out.exit_code == 3 and "degenerate 2 > 0" in out.message


def _ruled_hypar(tmp_path):
    """z = x y meshed along its rulings (an asymptotic net: no conical mesh near its own lines), noisy."""
    from optimize.mesh.io import write_mesh
    from optimize.modelling import shapes

    mesh = shapes.perturbed(shapes.grid(8, 7, size=(7000.0, 6000.0), height=lambda x, y: 0.5e-3 * x * y),
                            50.0, seed=14)
    write_mesh(tmp_path / "hypar.obj", mesh)
    return tmp_path / "hypar.obj"


def test_a_mesh_whose_own_lines_stall_takes_the_principal_remesh_and_says_why(tmp_path):
    """#30 item 1: the default (no target, input.remesh unset) tries the design's own lines, then a remesh
    along principal directions, and takes the one that builds; one paragraph says which and why."""
    src = _ruled_hypar(tmp_path)
    summary = run_pipeline(tiny_config(tmp_path, "hyp", outputs=MESH_ONLY, input={"mesh": str(src)},
                                       optimize={}), tmp_path / "out")
    assert summary.exit_code == 0, summary.message
    assert summary.decision.startswith("Route: conical by remeshed along principal directions, moving the design")
    assert "every beam planar to" in summary.decision and "Tried: own lines: stalled" in summary.decision
    report = json.loads((tmp_path / "out" / "hyp" / "report.json").read_text())
    routes = report["input"]["routes"]
    assert [r["chosen"] for r in routes] == [False, True] and routes[1]["target"] == "conical"
    assert report["decision"] == summary.decision and summary.decision in report["notes"]


def test_without_the_remesh_route_the_paragraph_says_pq_was_tried_and_what_may_help(tmp_path):
    src = _ruled_hypar(tmp_path)
    summary = run_pipeline(tiny_config(tmp_path, "hyp", outputs=MESH_ONLY, input={"mesh": str(src), "remesh": "never"},
                                       optimize={}), tmp_path / "out")
    assert summary.exit_code == 3
    d = summary.decision
    assert d.startswith("Route: no route reached its target; the nearest is own lines (stalled)")
    assert "Tried: PQ on own lines:" in d and d.endswith("What may help: input.remesh: auto (a remesh along "
                                                         "the principal directions of the design).")


def test_an_explicit_target_is_honoured_and_gets_the_same_diagnosis(tmp_path):
    src = _ruled_hypar(tmp_path)
    summary = run_pipeline(tiny_config(tmp_path, "hyp", outputs=MESH_ONLY, input={"mesh": str(src)},
                                       optimize={"target": "pq"}), tmp_path / "out")
    assert "Route: pq by" in summary.decision and "optimize.target: pq was asked for" in summary.decision
    assert "PQ on own lines" not in summary.decision  # no fallback route for an explicit target


def test_the_report_page_says_check_failed_or_export_failed_and_names_the_parts():
    from fabricate.report.html import failed_parts, status_words

    clash = {"pass": False, "checks": {"intersections": {"pass": False, "failures": [
        {"pair": ["B0012", "B0013"], "volume_mm3": 3.0}, {"pair": ["B0013", "N0004.1"], "volume_mm3": 1.0}]},
        "stl": {"pass": True}}}
    assert status_words({"status": "export_failed", "check": clash}) == "CHECK FAILED"
    assert failed_parts(clash) == ["B0012", "B0013", "N0004.1"]
    lost = {"pass": False, "checks": {"export model.stl": {"pass": False, "why": "model.stl: export failed"}}}
    assert status_words({"status": "export_failed", "check": lost}) == "EXPORT FAILED"
    assert status_words({"status": "tolerance_not_reached"}) == "TOLERANCE NOT REACHED"
    assert failed_parts(None) == [] and failed_parts({"checks": {"x": {"pass": True, "failures": [{"id": "P1"}]}}}) == []


def test_the_report_page_shows_the_route_and_names_worst_parts_by_id(tmp_path):
    run_pipeline(tiny_config(tmp_path, "page", outputs=dict(MESH_ONLY, html=True)), tmp_path / "out")
    page = (tmp_path / "out" / "page" / "report.html").read_text()
    report = json.loads((tmp_path / "out" / "page" / "report.json").read_text())
    worst = report["measures"]["planarity"]["worst"][0]["id"]
    assert f"{worst}: " in page


def test_a_surface_the_remesher_cannot_take_is_a_route_not_taken_not_bad_input(tmp_path, monkeypatch):
    """The remesher refusing the surface (it cannot tell which side is in) must not end the run (exit 2)
    when the design's own lines already gave a result: the route is listed as not taken, with why."""
    import optimize.remesh.routes as routes
    from optimize.errors import ConfigError

    def refuses(*args, **kwargs):
        raise ConfigError("tunnel.off: side vector [0.0, 0.0, -1.0] does not tell the two sides apart")

    monkeypatch.setattr(routes, "optimize_routes", refuses)
    summary = run_pipeline(tiny_config(tmp_path, "side", outputs=MESH_ONLY, input={"mesh": str(_ruled_hypar(tmp_path))},
                                       optimize={"target": "pq"}), tmp_path / "out")
    d = summary.decision
    assert "remeshed along principal directions: not taken (remeshing failed: tunnel.off: side vector" in d
    assert d.startswith("Route: no route reached its target; the nearest is own lines (stalled)")
    assert "the remesh along its principal directions could not be made (why: above)" in d
    assert "input.remesh: auto" not in d  # it is on: never advised


def test_an_export_error_names_the_run_folder_not_the_temporary_one(tmp_path, monkeypatch):
    import fabricate.export as export
    from optimize.errors import ExportError

    def fails(parts, path, **kwargs):
        raise ExportError(f"disk full writing {path}: cannot write the STL file (No space left on device)")

    monkeypatch.setattr(export, "write_stl", fails)
    cfg = tiny_config(tmp_path, "named", outputs=dict(MESH_ONLY, stl=True))
    summary = run_pipeline(cfg, tmp_path / "out")  # an exporter's own error: the rest is written, exit 4
    assert summary.exit_code == 4 and ".part" not in summary.message
    assert "export failed: disk full writing model.stl: cannot write the STL file" in summary.message


def test_the_rationalize_option_reaches_the_run(tmp_path):
    """optimize.rationalize (#37 item 3) is passed from the config to the optimizer: fewer glass shapes."""
    outputs = dict(MESH_ONLY, bom=True)
    plain = run_pipeline(tiny_config(tmp_path, "plain", outputs=outputs), tmp_path / "out")
    pulled = run_pipeline(tiny_config(tmp_path, "pulled", outputs=outputs,
                                      optimize={"target": "conical", "max_iter": 60, "rationalize": 100}),
                          tmp_path / "out")
    shapes = [json.loads((tmp_path / "out" / n / "report.json").read_text())["totals"]["glass_shapes"]
              for n in ("plain", "pulled")]
    assert pulled.exit_code in (0, 3) and plain.exit_code == 0
    assert shapes[1] < shapes[0], shapes


def test_every_run_holds_its_glass_order_to_the_panels(tmp_path, monkeypatch):
    """#36 item 5: the run's check reads glass_order.csv and its drawings back (a unit listed twice fails it)."""
    import fabricate.export.glass_order as order

    outputs = dict(MESH_ONLY, bom=True, glass_order=True, check="fast")
    good = run_pipeline(tiny_config(tmp_path, "order", outputs=outputs), tmp_path / "out")
    report = json.loads((tmp_path / "out" / "order" / "report.json").read_text())
    assert good.exit_code == 0 and report["check"]["checks"]["glass_order"]["pass"] is True
    real = order.write_glass_order

    def twice(parts, path, **kw):  # the writer lists the first unit in two positions
        import csv

        facts = real(parts, path, **kw)
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
        rows[1]["units"] += " " + rows[0]["units"].split()[0]
        rows[1]["quantity"] = str(len(rows[1]["units"].split()))
        with open(path, "w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
        return facts

    monkeypatch.setattr(order, "write_glass_order", twice)
    import fabricate.export as export
    monkeypatch.setattr(export, "write_glass_order", twice)
    bad = run_pipeline(tiny_config(tmp_path, "twice", outputs=outputs), tmp_path / "out")
    report = json.loads((tmp_path / "out" / "twice" / "report.json").read_text())
    assert bad.exit_code == 4 and "glass_order" in bad.message
    assert any("in positions" in p for p in report["check"]["checks"]["glass_order"]["problems"])


def test_beams_that_still_twist_get_a_route_with_the_node_axes_solved(tmp_path, monkeypatch):
    """#30 items 1, 4: a converged route whose (boundary) beams twist beyond the limit is tried again
    with the node axes solved by the optimizer (torsion_free_beams on: True, as the optimizer takes it)."""
    import fabricate.app.decide as decide
    import optimize.api as api

    twists = iter([5.0, 0.01])  # the own lines twist, the route with solved axes does not
    monkeypatch.setattr(decide, "beam_twist", lambda cfg, mesh, result: (next(twists), 0))
    seen = []
    real = api.optimize_mesh

    def spy(mesh, target, **kw):
        seen.append(kw.get("torsion_free_beams"))
        return real(mesh, target, **kw)

    monkeypatch.setattr(api, "optimize_mesh", spy)
    from optimize.mesh.io import write_mesh
    from optimize.modelling import shapes

    dome = shapes.perturbed(shapes.revolution(shapes.dome_profile(5000.0, 2000.0, 3), 6), 0.05, seed=3)
    write_mesh(tmp_path / "dome.obj", dome)
    summary = run_pipeline(tiny_config(tmp_path, "axes", outputs=MESH_ONLY,
                                       input={"mesh": str(tmp_path / "dome.obj"), "remesh": "never"},
                                       optimize={}), tmp_path / "out")
    assert True in seen
    assert "Route: conical by own lines, node axes solved with the mesh" in summary.decision
