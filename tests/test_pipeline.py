"""The pipeline end to end: the README quickstart, outcomes and exit codes, atomic output folders."""
from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile

import pytest

import fabricate.app.stages as stages
from fabricate.app.config import load_config
from fabricate.app.pipeline import STAGES, run_pipeline
from fabricate.app.progress import RecordingProgress
from optimize.errors import ConfigError, MeshError
from optimize.mesh.io import read_mesh

from _pipeline_fixtures import REPO, finished_run, tiny_config  # noqa: F401 - fixtures

EXPECTED = ("config.yaml", "mesh.obj", "layer_0.obj", "layer_1.obj", "model.step", "model.stl", "model.3mf",
            "outlines.dxf", "outlines.svg", "bom.csv", "report.json", "report.html", "model.glb",
            "model_glb.js", "assets/three-viewer.min.js", "planarity.png", "conical.png", "layers.png",
            "history.png", "sheets.png", "layout_plan.png")


# -- the README quickstart: python -m fabricate run configs/quickstart.yaml --------------------
def test_quickstart_command_succeeds_and_says_where(finished_run):
    assert finished_run.returncode == 0, finished_run.stderr[-2000:]
    assert "quickstart: ok" in finished_run.stdout
    assert str(finished_run.out / "report.html") in finished_run.stdout
    for stage in STAGES:  # one progress row per stage
        assert stage in finished_run.stderr


def test_quickstart_writes_every_file_and_they_are_valid(finished_run):
    out, report = finished_run.out, finished_run.report
    missing = [f for f in EXPECTED if not (out / f).is_file()]
    assert not missing, missing
    assert not list(out.parent.glob(".*"))  # no temporary folder beside the result
    # the mesh and the layers read back with the same faces
    mesh = read_mesh(out / "mesh.obj")
    assert (mesh.n_faces, mesh.n_vertices) == (report["result_mesh"]["faces"], report["result_mesh"]["vertices"])
    layer = read_mesh(out / "layer_1.obj")
    assert (layer.F == mesh.F).all()
    # the CAD files: STEP header, 3MF zip, SVG and DXF parse, BOM lists every part
    assert (out / "model.step").read_text(errors="replace").startswith("ISO-10303-21")
    with zipfile.ZipFile(out / "model.3mf") as z:
        assert any(n.endswith(".model") for n in z.namelist())
    ET.parse(out / "outlines.svg")
    import ezdxf

    assert len(ezdxf.readfile(out / "outlines.dxf").modelspace()) > 0
    bom = list(csv.DictReader((out / "bom.csv").open()))
    assert len(bom) >= report["parts"]["total"]["count"] > 0
    # the configuration as run loads again and gives the same settings
    again = load_config(out / "config.yaml")
    assert again.as_dict() == report["config"]
    # and the output check of the CAD stage agrees
    from fabricate.check import check_outputs

    assert _all_pass(check_outputs(out))


def _all_pass(check: dict) -> bool:
    if "pass" in check:
        return bool(check["pass"])
    return all(v.get("pass", True) for v in check.get("checks", {}).values() if isinstance(v, dict))


def test_quickstart_report_quotes_measures_with_tolerances(finished_run):
    report = finished_run.report
    assert report["status"] == "ok" and report["exit_code"] == 0
    m = report["measures"]
    assert m["planarity"]["pass"] and m["planarity"]["max"] <= m["planarity"]["tolerance"]
    assert m["conical"]["enforced"] and m["conical"]["pass"]
    assert m["beam_planarity"]["enforced"] and m["beam_planarity"]["max_twist_mm"] < 1e-3
    assert report["optimization"]["status"] == "converged"
    assert report["versions"]["numpy"] and report["versions"]["fabricate"]


# -- outcomes -----------------------------------------------------------------------------------
def test_progress_reports_every_stage_in_order(tmp_path):
    rec = RecordingProgress()
    summary = run_pipeline(tiny_config(tmp_path), tmp_path / "out", progress=rec)
    assert [s for e, s, _ in rec.events if e == "start"] == list(STAGES)
    assert [s for e, s, _ in rec.events if e == "done"] == list(STAGES)
    assert summary.status == "ok", summary.message
    assert sorted(p.name for p in (tmp_path / "out" / "tiny").iterdir()) == \
        [".conical-fab-run.json", "config.yaml", "layer_0.obj", "layer_1.obj", "mesh.obj", "report.json"]


def test_tolerance_not_reached_is_written_and_marked(tmp_path):
    cfg = tiny_config(tmp_path, "strict", outputs={"step": False, "stl": False, "3mf": False, "dxf": False,
                                                   "svg": False, "bom": False, "pictures": False, "html": True},
                      optimize={"target": "conical", "max_iter": 1})
    summary = run_pipeline(cfg, tmp_path / "out")
    out = tmp_path / "out" / "strict"
    assert summary.status == "tolerance_not_reached" and summary.exit_code == 3
    report = json.loads((out / "report.json").read_text())
    assert report["status"] == "tolerance_not_reached" and report["failed"]
    for name in report["failed"]:
        assert report["measures"][name]["pass"] is False and report["measures"][name]["enforced"]
    marker = (out / "TOLERANCE_NOT_REACHED.txt").read_text()
    assert report["failed"][0] in marker
    assert "TOLERANCE NOT REACHED" in (out / "report.html").read_text()


def test_cli_exit_codes_bad_input(tmp_path):
    broken = tmp_path / "broken.yaml"
    broken.write_text("input: {mesh: grid.obj}\nparts: {glass_thicknes: 8}\n")
    proc = _cli("run", str(broken), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 2
    assert "broken.yaml" in proc.stderr and "did you mean 'glass_thickness'" in proc.stderr
    bad_mesh = tmp_path / "bad.obj"
    bad_mesh.write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    cfg = tmp_path / "m.yaml"
    cfg.write_text("input: {mesh: bad.obj}\n")
    proc = _cli("run", str(cfg), "--out", str(tmp_path / "out"), "-q", cwd=tmp_path)
    assert proc.returncode == 2 and "bad.obj:3" in proc.stderr
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def _cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "fabricate", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=300, env=dict(os.environ, PYTHONPATH=str(REPO)))


def test_export_failure_is_exit_4_with_the_other_files_and_the_report_written(tmp_path, monkeypatch):
    """An exporter that raises loses nothing else: the mesh, the other files and the report are
    written, marked (CHECK_FAILED.txt), and the run ends 4 naming the file and the error (#30)."""
    import fabricate.export as export

    def broken_writer(parts, path):
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(export, "write_stl", broken_writer)
    cfg = tiny_config(tmp_path, "exp", outputs={"stl": True, "step": False, "3mf": False, "dxf": False,
                                                "svg": True, "bom": False, "pictures": False, "html": False})
    summary = run_pipeline(cfg, tmp_path / "out")
    assert (summary.status, summary.exit_code) == ("export_failed", 4)
    assert "export failed: model.stl: export failed: RuntimeError: disk on fire" in summary.message
    out = tmp_path / "out" / "exp"
    assert (out / "mesh.obj").is_file() and (out / "outlines.svg").is_file() and not (out / "model.stl").exists()
    assert (out / "CHECK_FAILED.txt").is_file()
    report = json.loads((out / "report.json").read_text())
    assert report["exit_code"] == 4 and report["check"]["checks"]["export model.stl"]["pass"] is False


def test_a_full_disk_while_exporting_still_leaves_nothing(tmp_path, monkeypatch):
    """No file can be written after a full disk (the report neither): nothing is left (exit 4)."""
    import errno

    import fabricate.export as export

    def full(parts, path):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(export, "write_stl", full)
    cfg = tiny_config(tmp_path, "full", outputs={"stl": True, "step": False, "3mf": False, "dxf": False,
                                                 "svg": False, "bom": False, "pictures": False, "html": False})
    with pytest.raises(OSError, match="No space left") as err:
        run_pipeline(cfg, tmp_path / "out")
    assert list((tmp_path / "out").iterdir()) == []
    # the message names the run folder's file, not the hidden temporary folder that is gone
    assert err.value.filename == str(tmp_path / "out" / "full" / "model.stl")


def test_failed_output_check_is_exit_4_written_and_marked(tmp_path, monkeypatch):
    import fabricate.check as check

    def failing_check(outdir, tol=None, **kwargs):
        return {"pass": False, "checks": {"bom": {"pass": True}, "stl": {"pass": False, "why": "injected"}}}

    monkeypatch.setattr(check, "check_outputs", failing_check)
    cfg = tiny_config(tmp_path, "chk", outputs={"bom": True, "step": False, "stl": False, "3mf": False,
                                                "dxf": False, "svg": False, "pictures": False, "html": False})
    summary = run_pipeline(cfg, tmp_path / "out")
    assert (summary.status, summary.exit_code) == ("export_failed", 4)
    assert "check:stl" in summary.failed
    out = tmp_path / "out" / "chk"
    assert "failed the output check" in (out / "CHECK_FAILED.txt").read_text()
    assert json.loads((out / "report.json").read_text())["check"]["checks"]["stl"]["why"] == "injected"


# -- atomic output folders ------------------------------------------------------------------------
@pytest.mark.parametrize("stage,error", [("report", RuntimeError), ("exports", KeyboardInterrupt),
                                         ("offset", MeshError)])
def test_failure_in_a_stage_leaves_no_folder(tmp_path, monkeypatch, stage, error):
    original = getattr(stages, f"stage_{stage}")

    def fail_after(*args, **kwargs):
        original(*args, **kwargs)  # the stage has written its files into the temporary folder
        raise error("injected")

    monkeypatch.setattr(stages, f"stage_{stage}", fail_after)
    with pytest.raises(error):
        run_pipeline(tiny_config(tmp_path), tmp_path / "out")
    assert list((tmp_path / "out").iterdir()) == []  # neither outputs/tiny nor a temporary folder


def test_rerun_replaces_only_when_complete(tmp_path, monkeypatch):
    out = tmp_path / "out"
    first = run_pipeline(tiny_config(tmp_path), out)
    before = (out / "tiny" / "report.json").read_text()
    monkeypatch.setattr(stages, "stage_report", lambda run: (_ for _ in ()).throw(RuntimeError("late")))
    with pytest.raises(RuntimeError):
        run_pipeline(tiny_config(tmp_path), out, force=True)
    assert (out / "tiny" / "report.json").read_text() == before  # the previous result is untouched
    monkeypatch.undo()
    second = run_pipeline(tiny_config(tmp_path), out, force=True)
    assert second.status == first.status
    assert [p.name for p in out.iterdir()] == ["tiny"]  # no temporary or old folder left
    assert json.loads((out / "tiny" / "report.json").read_text())["created_utc"]


def test_sigterm_during_a_run_leaves_no_folder(tmp_path):
    """``kill`` of a running ``fabricate run`` unwinds like Ctrl-C: the temporary folder is removed."""
    cfg = tmp_path / "slow.yaml"
    cfg.write_text("name: slow\ninput:\n  shape: {name: dome, params: {meridians: 6, rings: 3}}\n")
    driver = ("import sys, time\nimport fabricate.app.stages as s\n"
              "def slow(*args, **kwargs):\n    print('IN CAD', flush=True)\n    time.sleep(120)\n"
              "s.stage_cad = slow\nfrom fabricate.app.cli import main\n"
              f"sys.exit(main(['run', {str(cfg)!r}, '--out', {str(tmp_path / 'out')!r}, '-q']))\n")
    proc = subprocess.Popen([sys.executable, "-c", driver], cwd=REPO, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "IN CAD"
        assert any((tmp_path / "out").iterdir())  # the temporary folder exists while it runs
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, proc.stderr.read()
    assert list((tmp_path / "out").iterdir()) == []


def test_input_mesh_is_not_changed_and_units_convert(tmp_path, monkeypatch):
    """A mesh file in metres comes out in mm; the stages never mutate what they are given."""
    from optimize.modelling import shapes
    from optimize.mesh.io import write_mesh

    mesh = shapes.revolution(shapes.dome_profile(6.0, 2.0, 4), 8)  # metres, exactly conical
    write_mesh(tmp_path / "dome_m.obj", mesh)
    (tmp_path / "m.yaml").write_text("input: {mesh: dome_m.obj}\nunits: m\noptimize: {target: conical}\n"
                                     "outputs: {step: false, stl: false, 3mf: false, dxf: false, svg: false, "
                                     "bom: false, pictures: false, html: false}\n")
    summary = run_pipeline(load_config(tmp_path / "m.yaml"), tmp_path / "out")
    assert summary.status == "ok", summary.message
    out = read_mesh(tmp_path / "out" / "m" / "mesh.obj")
    assert out.bbox_diagonal() == pytest.approx(mesh.bbox_diagonal() * 1000.0, rel=1e-6)
    assert read_mesh(tmp_path / "dome_m.obj").V.tolist() == mesh.V.tolist()


def test_folded_panels_write_no_cut_file_and_end_marked(tmp_path, capsys):
    """Planar to tolerance but dented: z = x y meshed along its rulings, noisy boundary fixed.
    The optimizer says "folded"; no panel or beam is built and no cut file written, but the mesh,
    the layers and the report are, marked as a missed tolerance (exit 3), with the faces named."""
    from fabricate.app.cli import main
    from optimize import optimize_mesh
    from optimize.modelling import shapes
    from optimize.mesh.io import write_mesh

    mesh = shapes.perturbed(shapes.grid(8, 7, size=(7000.0, 6000.0),
                                        height=lambda x, y: 0.5e-3 * x * y), 50.0, seed=14)
    assert optimize_mesh(mesh, "pq", fixed="boundary", convex=False).status == "folded"
    write_mesh(tmp_path / "hypar.obj", mesh)
    (tmp_path / "f.yaml").write_text("input: {mesh: hypar.obj, remesh: never}\noptimize: {target: pq, "
                                     "fixed: boundary, convex: false}\n")
    code = main(["run", str(tmp_path / "f.yaml"), "--out", str(tmp_path / "out")])
    cap = capsys.readouterr()
    err = cap.err
    assert code == 3 and "folded" in err and "no panels or beams built" in err
    assert cap.out.startswith("Route: no route reached its target; the nearest is own lines (folded)")
    assert "What may help: input.remesh: auto" in cap.out and "optimize.target: pq was asked for" in cap.out
    out = tmp_path / "out" / "f"
    assert (out / "TOLERANCE_NOT_REACHED.txt").exists() and (out / "mesh.obj").exists()
    for name in ("model.step", "model.stl", "model.3mf", "outlines.dxf", "outlines.svg", "bom.csv"):
        assert not (out / name).exists(), name
    report = json.loads((out / "report.json").read_text())
    assert report["exit_code"] == 3 and "folded" in report["failed"] and report["parts"] is None


def test_design_parameter_error_from_the_config(tmp_path):
    (tmp_path / "d.yaml").write_text("input:\n  shape: {name: dome, params: {rings: 1}}\n")
    with pytest.raises(ConfigError, match=r"d.yaml:2: input.shape: .*rings=1"):
        load_config(tmp_path / "d.yaml")


def test_surface_input_is_remeshed_into_quads(tmp_path):
    """A triangle surface (a saddle in metres) goes through remeshing, then the whole pipeline."""
    from optimize import Mesh
    from optimize.modelling import shapes
    from optimize.mesh.io import write_mesh

    g = shapes.grid(12, 12, size=(6.0, 6.0), height=lambda X, Y: 0.15 * ((X - 3) ** 2 - 0.5 * (Y - 3) ** 2))
    write_mesh(tmp_path / "saddle.obj", Mesh(g.V, g.triangulate(), name="saddle"))
    (tmp_path / "s.yaml").write_text("input: {surface: saddle.obj, edge_length: 2.0, radius: 2.5}\nunits: m\n"
                                     "outputs: {step: false, stl: false, 3mf: false, dxf: false, svg: false, "
                                     "bom: false, pictures: false, html: false}\n")
    summary = run_pipeline(load_config(tmp_path / "s.yaml"), tmp_path / "out")
    report = json.loads((tmp_path / "out" / "s" / "report.json").read_text())
    assert report["input"]["kind"] == "surface" and report["input"]["remesh"]["faces"] == summary.faces
    assert report["input"]["remesh"]["radius"] == 2.5  # input.radius, in the input's units
    mesh = read_mesh(tmp_path / "out" / "s" / "mesh.obj")
    assert (mesh.face_sizes == 4).mean() > 0.5  # quad-dominant
    assert summary.status in ("ok", "tolerance_not_reached"), summary.message


def test_atrium_roof_goes_from_a_triangle_surface_to_cut_files(tmp_path):
    """configs/atrium_roof.yaml: a triangle mesh with an opening -> principal quads -> conical with a
    gliding boundary -> panels and beams, STEP / STL / DXF / BOM, every enforced tolerance met."""
    from optimize.remesh import surfaces

    shipped = read_mesh(REPO / "configs" / "surfaces" / "atrium_roof.obj")
    made = surfaces.holed_roof(scale=6000.0)  # the shipped file is what the docstring says it is
    assert shipped.n_faces == made.n_faces and abs(shipped.V - made.V).max() < 1e-6
    cfg = load_config(REPO / "configs" / "atrium_roof.yaml",   # exchange files and the full check: small cases
                      {"outputs.pictures": False, "outputs.html": False, "outputs.3mf": False, "outputs.check": "fast",
                       "outputs.ifc": False, "outputs.3dm": False, "outputs.nc1": False, "outputs.gltf": False})
    summary = run_pipeline(cfg, tmp_path)
    assert summary.exit_code == 0 and summary.status == "ok", summary.message
    out = tmp_path / "atrium_roof"
    report = json.loads((out / "report.json").read_text())
    assert report["input"]["kind"] == "surface"
    mesh = read_mesh(out / "mesh.obj")
    assert len(mesh.topology.boundary_loops) == 2  # the opening is still there
    m = report["measures"]
    assert m["planarity"]["pass"] and m["conical"]["pass"] and m["folded"]["max"] == 0
    assert m["beam_planarity"]["pass"] and m["closeness"]["max"] < 0.005
    # closeness is measured to the user's triangle surface (the optimizer's reference), not to the quads
    from optimize.proximity import Reference

    dist = Reference(shipped).distance(mesh.V).max()
    assert dist == pytest.approx(m["closeness"]["max_mm"], rel=1e-3, abs=1e-3)
    rows = list(csv.DictReader((out / "bom.csv").open()))
    kinds = [r["kind"] for r in rows]
    units = {r["unit"] for r in rows if r["kind"] == "panel"}  # an insulated unit: 4 solids (plies, PVB)
    assert len(units) == mesh.n_faces and kinds.count("panel") == 4 * mesh.n_faces
    beams = {r["unit"] for r in rows if r["kind"] == "beam"}   # one beam of plates (an RHS: six) per edge
    assert len(beams) == len(mesh.topology.edges) and kinds.count("beam") == 6 * len(beams)
    for name in ("model.step", "model.stl", "outlines.dxf", "outlines.svg", "bom.csv"):
        assert (out / name).stat().st_size > 0


def test_a_tube_from_a_real_mesh_through_the_pipeline(tmp_path):
    """shapes.capped_cylinder() without its caps, in metres, as a surface with ``side: keep``: remeshed along its
    circles and rulings, conical, offset and built into panels and beams (exit 0)."""
    import numpy as np

    from optimize import Mesh
    from optimize.modelling import shapes
    from optimize.mesh.io import write_mesh

    m = shapes.capped_cylinder()
    quads = m.F[m.face_sizes == 4][:, :4]
    used = np.unique(quads)
    remap = np.full(m.n_vertices, -1)
    remap[used] = np.arange(len(used))
    write_mesh(tmp_path / "tube.obj", Mesh(m.V[used], remap[quads], name="tube"))
    (tmp_path / "t.yaml").write_text("input: {surface: tube.obj, edge_length: 0.3, side: keep}\nunits: m\n"
                                     "outputs: {step: false, stl: false, 3mf: false, svg: false, "
                                     "pictures: false, html: false}\n")
    summary = run_pipeline(load_config(tmp_path / "t.yaml"), tmp_path / "out")
    assert summary.exit_code == 0, summary.message
    report = json.loads((tmp_path / "out" / "t" / "report.json").read_text())
    assert report["input"]["remesh"]["method"] == "seamless"
    assert report["measures"]["conical"]["pass"] and report["measures"]["beam_planarity"]["pass"]
    rows = list(csv.DictReader((tmp_path / "out" / "t" / "bom.csv").open()))
    assert sum(r["kind"] == "panel" for r in rows) == summary.faces


# -- outputs.check: full | fast | off | auto -------------------------------------------------------
CAD_FILES = {"step": True, "stl": True, "3mf": True, "dxf": True, "svg": True, "bom": True,
             "pictures": False, "html": False}


def exact_config(folder, name, check):
    """The tiny dome without noise and without optimization (conical by construction), all CAD files."""
    return tiny_config(folder, name, outputs=dict(CAD_FILES, check=check), optimize={"target": "none"},
                       input={"shape": {"name": "dome", "params": {"radius": 5000, "rise": 2000, "meridians": 6,
                                                                    "rings": 3}}})


def test_fast_check_skips_the_step_read_back_and_still_catches_bad_files(tmp_path):
    from fabricate.check_fast import run_check

    summary = run_pipeline(exact_config(tmp_path, "fast", "fast"), tmp_path / "out")
    assert summary.status == "ok", summary.message
    out = tmp_path / "out" / "fast"
    check = json.loads((out / "report.json").read_text())["check"]
    assert (check["mode"], check["mode_asked"], check["pass"]) == ("fast", "fast", True)
    assert check["checks"]["step"]["read_back"] is False and check["checks"]["step"]["solids"] == summary.parts
    assert check["checks"]["dxf"]["against"] == "bom" and check["checks"]["dxf"]["outlines"] > 0
    assert all(check["checks"][k]["pass"] for k in ("bom", "3mf", "stl", "intersections", "bearing", "svg"))
    full = run_check(out, "full")  # the full check of the same files agrees, reading the STEP back
    assert full["mode"] == "full" and full["pass"] and full["checks"]["step"]["read_back"] == "text"
    step = (out / "model.step").read_text()
    (out / "model.step").write_text(step.replace("'P0001'", "'P9999'"))
    renamed = run_check(out, "fast")["checks"]["step"]
    assert not renamed["pass"] and renamed["missing"] == ["P0001"] and renamed["unexpected"] == ["P9999"]
    (out / "model.step").write_text(step[: len(step) // 2])
    assert not run_check(out, "fast")["checks"]["step"]["complete"]
    rows = list(csv.reader((out / "bom.csv").open()))
    area = rows[0].index("area_m2")
    rows[1][area] = f"{float(rows[1][area]) + 1e-5:.6f}"  # 10 mm2 more than the outline in the DXF
    with (out / "bom.csv").open("w", newline="") as fh:
        csv.writer(fh).writerows(rows)
    dxf = run_check(out, "fast")["checks"]["dxf"]
    assert not dxf["pass"] and dxf["failures"][0]["id"] == rows[1][0]


def test_check_off_and_auto(tmp_path):
    summary = run_pipeline(exact_config(tmp_path, "off", "off"), tmp_path / "out")
    assert summary.status == "ok" and summary.exit_code == 0
    check = json.loads((tmp_path / "out" / "off" / "report.json").read_text())["check"]
    assert check["mode"] == "off" and check["pass"] is None and check["checks"] == {}
    from fabricate.app.config import CHECK_AUTO_MAX_PARTS

    auto = tiny_config(tmp_path, outputs=CAD_FILES).outputs
    assert auto.check == "auto"
    assert auto.check_mode(CHECK_AUTO_MAX_PARTS) == "full" and auto.check_mode(CHECK_AUTO_MAX_PARTS + 1) == "fast"
    with pytest.raises(ConfigError, match=r"outputs.check.*'quick'.*full.*fast.*off"):
        tiny_config(tmp_path, outputs=dict(CAD_FILES, check="quick"))
