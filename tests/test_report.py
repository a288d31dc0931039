"""Reports: the GLB writer, the pictures, the measures table, and report.html in a real browser."""
from __future__ import annotations

import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from fabricate.report import GlbMesh, build_scene, glb_bytes, read_accessor, read_glb
from fabricate.report.glb import Z_UP_TO_Y_UP
from fabricate.report.html import ASSETS, VIEWER_FILES, copy_viewer
from fabricate.report.measures import entry, planarity_scale
from fabricate.report.pictures import picture_defect, picture_history, picture_layers
from optimize.mesh import measures
from optimize.modelling import shapes

from _pipeline_fixtures import finished_run  # noqa: F401 - a fixture


# -- GLB -------------------------------------------------------------------------
_GLTF_DTYPES = {5121: np.uint8, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_GLTF_WIDTH = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}


def _pygltf_accessor(doc, blob, index):
    """An accessor's array, read with pygltflib's document (the glTF 2.0 layout, not the project's code)."""
    acc = doc.accessors[index]
    view = doc.bufferViews[acc.bufferView]
    width = _GLTF_WIDTH[acc.type]
    data = np.frombuffer(blob, _GLTF_DTYPES[acc.componentType], acc.count * width,
                         (view.byteOffset or 0) + (acc.byteOffset or 0))
    return data.reshape(acc.count, width) if width > 1 else data


def test_glb_round_trip_keeps_geometry(revolution, tmp_path):
    """model.glb read back by pygltflib (an independent reader): names, positions in metres y-up,
    triangles, bounds and the edge lines."""
    import pygltflib

    mesh = revolution.with_vertices(revolution.V * 1000.0)  # planar quads, in mm
    scene = build_scene(mesh, measures.planarity(mesh), tolerance=1e-6)
    (tmp_path / "model.glb").write_bytes(glb_bytes(scene))
    doc = pygltflib.GLTF2().load(str(tmp_path / "model.glb"))
    blob = doc.binary_blob()
    assert doc.asset.version == "2.0"
    assert [m.name for m in doc.meshes] == [m.name for m in scene]
    design = doc.meshes[0].primitives[0]
    P = _pygltf_accessor(doc, blob, design.attributes.POSITION).astype(float)
    T = _pygltf_accessor(doc, blob, design.indices).reshape(-1, 3)
    expected = scene[0].positions @ Z_UP_TO_Y_UP.T * 1e-3  # mm, z up -> m, y up
    np.testing.assert_allclose(P, expected, rtol=1e-6, atol=1e-9)
    np.testing.assert_array_equal(T, scene[0].indices)
    acc = doc.accessors[design.attributes.POSITION]
    np.testing.assert_allclose(acc.min, P.min(axis=0), rtol=1e-6)
    # the triangles cover the planar faces: same total area (m^2 = mm^2 * 1e-6)
    tri_area = 0.5 * np.linalg.norm(np.cross(P[T[:, 1]] - P[T[:, 0]], P[T[:, 2]] - P[T[:, 0]]), axis=1).sum()
    assert tri_area == pytest.approx(measures.face_areas(mesh).sum() * 1e-6, rel=1e-3)
    edges = doc.meshes[1].primitives[0]
    assert edges.mode == 1 and doc.accessors[edges.indices].count == 2 * len(mesh.topology.edges)
    ours, binary = read_glb(glb_bytes(scene))  # the project's reader (the report check uses it) agrees
    np.testing.assert_array_equal(read_accessor(ours, binary, ours["meshes"][0]["primitives"][0]["indices"])
                                  .reshape(-1, 3), T)


def test_glb_layout_is_aligned_and_checked():
    P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]])
    data = glb_bytes([GlbMesh("t", P, np.array([[0, 1, 2]]), colors=np.ones((3, 3)))])
    assert len(data) % 4 == 0 and data[:4] == b"glTF"
    doc, binary = read_glb(data)
    assert all(v["byteOffset"] % 4 == 0 for v in doc["bufferViews"])
    with pytest.raises(ValueError, match="indices range"):
        glb_bytes([GlbMesh("bad", P, np.array([[0, 1, 3]]))])
    with pytest.raises(ValueError, match="header says"):
        read_glb(data[:-4])


def test_scene_face_colours_follow_planarity():
    grid = shapes.grid(3, 3)  # 4 quads
    scene = build_scene(grid, np.array([1e-9, 1e-2, 1e-9, 1e-2]), tolerance=1e-6)
    colours = scene[0].colors.reshape(grid.n_faces, 4, 4)  # 4 unshared corners per quad
    assert np.all(colours == colours[:, :1])  # one flat colour per face
    np.testing.assert_array_equal(colours[0], colours[2])
    assert colours[1, 0, 1] > colours[0, 0, 1] + 0.3  # viridis: the worse face is brighter


# -- measures -----------------------------------------------------------------------
def test_planarity_scale_turns_relative_into_mm(revolution):
    mesh = revolution.with_vertices(revolution.V * 1000.0)
    q = mesh.F[0]
    d = 0.5 * (np.linalg.norm(mesh.V[q[2]] - mesh.V[q[0]]) + np.linalg.norm(mesh.V[q[3]] - mesh.V[q[1]]))
    assert planarity_scale(mesh)[0] == pytest.approx(d)


def test_measure_entry_names_worst_elements():
    e = entry(np.array([1e-9, 5e-3, 2e-7]), 1e-6, "relative", "face", ids=np.array([10, 11, 12]),
              enforced=True, extra={"mm": np.array([1e-6, 5.0, 2e-4])})
    assert e["pass"] is False and e["max"] == 5e-3 and e["max_mm"] == 5.0
    assert [w["face"] for w in e["worst"]] == [11, 12, 10]
    assert e["worst"][0]["mm"] == 5.0
    assert entry(np.array([]), 1e-6, "rad", "vertex")["pass"] is True


# -- pictures -------------------------------------------------------------------------
def _png_ok(path: Path) -> None:
    from matplotlib.image import imread

    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    img = imread(path)
    assert img.shape[0] > 200 and img.shape[1] > 200
    assert img[..., :3].std() > 0.05  # not a blank canvas


def test_pictures_are_real_images(tmp_path, perturbed_revolution):
    mesh = perturbed_revolution
    picture_defect(mesh, measures.planarity(mesh), tmp_path / "p.png", title="p", label="planarity",
                   tolerance=1e-6)
    picture_defect(mesh, measures.conical_defect(mesh), tmp_path / "c.png", title="c", label="rad",
                   tolerance=1e-6, vertices=mesh.topology.interior_valence4)
    e = mesh.topology.edges
    L = mesh.V - [0, 0, 0.5]
    Q = np.stack([mesh.V[e[:, 0]], mesh.V[e[:, 1]], L[e[:, 1]], L[e[:, 0]]], axis=1)
    picture_layers([mesh.V, L], e, Q, tmp_path / "l.png", title="l", distances=(0, -500))
    hist = [{"planarity": 10.0 ** -k, "conical": 10.0 ** (-k / 2)} for k in range(8)]
    picture_history([("level 1", hist), ("level 2", hist)], tmp_path / "h.png",
                    tolerances={"planarity": 1e-6, "conical": 1e-6}, title="h")
    picture_history([], tmp_path / "h0.png", tolerances={}, title="no history")
    for name in ("p", "c", "l", "h", "h0"):
        _png_ok(tmp_path / f"{name}.png")
    assert not list(tmp_path.glob(".*"))  # no temporary files left


# -- the viewer assets -------------------------------------------------------------------
def test_viewer_bundle_is_vendored_with_its_licence():
    js = (ASSETS / "three-viewer.min.js").read_text()
    assert js.startswith("/*! three.js") and "SPDX-License-Identifier: MIT" in js
    assert "FabViewer" in js and "import " not in js[:2000]  # a classic script, not an ES module
    assert (ASSETS / "three-viewer.min.js").stat().st_size < 1_500_000
    assert "MIT License" in (ASSETS / "three.LICENSE").read_text()


def test_copy_viewer_writes_assets_and_embedded_model(tmp_path):
    glb = glb_bytes([GlbMesh("t", np.eye(3), np.array([[0, 1, 2]]))])
    files = copy_viewer(tmp_path, glb)
    assert sorted(files) == sorted([f"assets/{n}" for n in VIEWER_FILES] + ["model_glb.js"])
    import base64

    text = (tmp_path / "model_glb.js").read_text()
    assert base64.b64decode(re.search(r'"([A-Za-z0-9+/=]+)"', text).group(1)) == glb


# -- a real browser ---------------------------------------------------------------------------
def chromium_path() -> str | None:
    return next((p for p in map(shutil.which, ("chromium", "chromium-browser", "google-chrome")) if p), None)


def browser_dom(html: Path, tmp_path: Path) -> str:
    """The DOM of ``html`` after its scripts ran, from headless chromium (no network)."""
    exe = chromium_path()
    if exe is None:
        pytest.skip("chromium is not installed (apt-get install chromium); CI installs it")
    cmd = [exe, "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
           "--disable-background-networking", "--disable-dev-shm-usage", "--no-first-run",
           "--disable-extensions", "--disable-sync", f"--user-data-dir={tmp_path / 'chromium-profile'}",
           "--virtual-time-budget=15000", "--window-size=1200,900", "--dump-dom", html.resolve().as_uri()]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout


def viewer_state(dom: str) -> dict[str, str]:
    tag = re.search(r'<div id="view"[^>]*>', dom)
    assert tag, "report.html has no 3D view element"
    return dict(re.findall(r'data-([a-z]+)="([^"]*)"', tag.group(0)))


def test_report_html_3d_view_in_headless_chromium(finished_run, tmp_path):
    """report.html opened from disk: the GLB is parsed by three.js and a frame is drawn."""
    out = finished_run.out
    dom = browser_dom(out / "report.html", tmp_path)
    state = viewer_state(dom)
    assert state.get("viewer") == "ready", state
    doc, binary = read_glb((out / "model.glb").read_bytes())
    triangles = sum(doc["accessors"][p["indices"]]["count"] // 3 for m in doc["meshes"]
                    for p in m["primitives"] if p.get("mode", 4) == 4)
    meshes = sum(1 for m in doc["meshes"] if m["primitives"][0].get("mode", 4) == 4)
    assert int(state["meshes"]) == meshes and int(state["triangles"]) == triangles
    assert float(state["painted"]) > 0.01  # the model covers part of the canvas
    assert "[3D ready]" in re.search(r"<title>(.*?)</title>", dom).group(1)


def test_report_json_and_html_content(finished_run):
    out = finished_run.out
    report = json.loads((out / "report.json").read_text())
    assert report["name"] == finished_run.summary.name
    for key in ("config", "versions", "timings_s", "measures", "files", "input"):
        assert report[key], key
    for stage in ("input", "optimize", "offset", "cad", "exports", "before_report"):
        assert report["timings_s"][stage] >= 0
    plan = report["measures"]["planarity"]
    assert {"max", "tolerance", "pass", "worst", "max_mm", "unit"} <= set(plan)
    assert plan["pass"] == (plan["max"] <= plan["tolerance"])
    html = (out / "report.html").read_text()
    for name in report["pictures"]:
        assert f'src="{name}"' in html and (out / name).is_file()
        _png_ok(out / name)
    assert "http://" not in html and "https://" not in html  # nothing from the network


# -- the client's totals, masses, readable outline ids (issue 14) ----------------------------------
def test_distinct_sizes_are_congruence_classes_within_a_mm():
    from fabricate.report.totals import distinct_sizes

    q = np.array([[0.0, 0.0], [1500.0, 0.0], [1400.0, 900.0], [100.0, 1000.0]])  # no symmetry
    rot = np.array([[0.6, -0.8], [0.8, 0.6]])
    same = [q, np.roll(q, 1, axis=0) @ rot.T + 300.0, q + [0.4, -0.3]]           # moved, relabelled, 0.5 mm
    mirror = q * [-1.0, 1.0]
    off = q + [[0, 0], [2.5, 0], [0, 0], [0, 0]]                                 # one corner 2.5 mm out
    flat = np.stack(same + [mirror[::-1], off])                                  # the mirror kept ccw
    labels = distinct_sizes(flat, np.full(len(flat), 10.0))
    assert len(set(labels[:3])) == 1 and len(set(labels)) == 3
    thick = distinct_sizes(np.stack([q, q]), np.array([10.0, 12.0]))
    assert thick[0] != thick[1]


def test_totals_of_a_dome_count_rings_of_congruent_panels():
    from cad_fixtures import dome_structure

    from fabricate.cad import PartSpec, build_parts
    from fabricate.report.totals import client_totals, totals_lines

    s = dome_structure(n_around=8, k=4)
    parts = build_parts(s, PartSpec())
    t = client_totals(parts)
    rings = s.mesh.n_faces // 8
    assert t["panels"] == s.mesh.n_faces and t["distinct_panel_sizes"] == rings  # one size per ring
    assert t["most_panels_of_one_size"] == 8
    mesh_area = float(measures.face_areas(s.mesh).sum()) * 1e-6
    assert 0.8 * mesh_area < t["glass_area_m2"] < mesh_area  # inset by the joints
    edges = s.mesh.V[s.mesh.topology.edges]
    total_edges = float(np.linalg.norm(edges[:, 1] - edges[:, 0], axis=1).sum()) * 1e-3
    assert 0.8 * total_edges < t["steel_length_m"] <= 1.0001 * total_edges
    steel = sum(float(g.volume_mm3.sum()) for k in ("beam", "node") for g in parts.of_kind(k))
    assert t["steel_mass_kg"] == pytest.approx(steel * 1e-9 * parts.spec.density_steel)
    assert t["steel_mass_t"] == pytest.approx(t["steel_mass_kg"] / 1000)
    lines = totals_lines(t)
    assert f"{rings} distinct sizes" in lines[0] and " t with the nodes" in lines[1]


def test_masses_print_as_kilograms_not_exponents():
    from fabricate.report.totals import kg

    assert kg(2640.4) == "2,640 kg" and kg(12.46) == "12.5 kg" and "e+" not in kg(2.64e7)


def test_outline_ids_fit_their_parts(tmp_path):
    from fabricate.report.pictures import _id_patch, outline_label_sizes

    w, h = np.array([600.0, 25.0, 300.0]), np.array([400.0, 30.0, 4.0])
    ids = ["P0001", "B0002", "B0003"]
    fs = outline_label_sizes(w, h, ids)
    assert fs[0] == 9.0 and 3.0 <= fs[1] < 9.0 and fs[2] == 0.0  # the last is too thin: not drawn
    for text, f, width, height in zip(ids, fs, w, h):
        if f:
            ext = _id_patch([(text, np.zeros(2), f)]).get_path().get_extents()
            assert ext.width <= 0.9 * width and ext.height <= height  # drawn inside its part (pt = mm here)


def test_a_tall_narrow_part_has_its_id_turned_along_it():
    """A web strip on a nested sheet (25 x 400 pt) is too narrow for an upright id: it is drawn turned,
    bottom to top, and its ink stays inside the strip."""
    from fabricate.report.pictures import _id_patch, outline_label_sizes, upright_or_turned

    w, h, ids = np.array([25.0, 600.0]), np.array([400.0, 400.0]), ["B0137.1", "P0001"]
    fs, turned = upright_or_turned(w, h, ids)
    assert outline_label_sizes(w, h, ids)[0] < fs[0] and list(turned) == [True, False]
    ext = _id_patch([(ids[0], np.zeros(2), fs[0], True)]).get_path().get_extents()
    assert ext.height > ext.width and ext.width <= w[0] and ext.height <= 0.9 * h[0]
    up = _id_patch([(ids[0], np.zeros(2), fs[0])]).get_path().get_extents()
    assert ext.width == pytest.approx(up.height) and ext.height == pytest.approx(up.width)


def test_sheet_and_plan_pictures_come_from_the_nested_cut_files(tmp_path):
    """sheets.png draws the real nesting of the cut files (the same Layout the DXF is written from):
    the fullest glass and steel sheet, every part on it placed inside the sheet's margin."""
    from cad_fixtures import dome_parts
    from fabricate.app.config_parts import NestingSection
    from fabricate.export.cutfiles import nest_cut_files
    from fabricate.report.shop_pictures import picture_plan, picture_sheets, plan_drawing, sheet_drawings

    parts = dome_parts()
    batches = nest_cut_files(parts, NestingSection().model_dump())
    sheets = sheet_drawings(batches)
    assert [s["material"] for s in sheets] == ["glass", "steel"]
    for s in sheets:
        lay = next(b["layout"] for b in batches if b["stem"] + ".dxf" == s["file"])
        k = int(s["id"].rsplit("-S", 1)[1]) - 1
        assert s["parts"] == int((lay.sheet == k).sum()) and s["yield"] == pytest.approx(lay.utilisation.max())
        W, H = s["size"]
        for _, q in s["outlines"]:
            assert q.min() >= s["margin"] - 1e-6 and (q.max(axis=0) <= np.array([W, H]) - s["margin"] + 1e-6).all()
    _png_ok(picture_sheets(sheets, tmp_path / "sheets.png", title="t"))
    plan = plan_drawing(parts)
    assert {i for i, _ in plan["panels"]} == {p.id for p in parts.panels}
    _png_ok(picture_plan(plan, tmp_path / "plan.png", title="t"))


def test_report_has_the_clients_totals(finished_run):
    report = json.loads((finished_run.out / "report.json").read_text())
    t = report["totals"]
    assert t["panels"] == report["parts"]["panels"]["count"] and t["distinct_panel_sizes"] >= 1
    assert t["glass_area_m2"] > 0 and t["steel_length_m"] > 0 and t["steel_mass_t"] > 0
    html = (finished_run.out / "report.html").read_text()
    assert "distinct sizes" in html and "m2 in" in html
    assert not re.search(r"\d\.\d+e\+\d\d", html.split("<h2>Timings")[0]), "a mass printed as an exponent"
    assert "distinct sizes" in finished_run.stdout


def test_failed_parts_are_drawn_apart_in_the_3d_view():
    """#30 item 7: the parts a failed check or requirement names are one red primitive of the view (a
    toggle named by their ids), and the kinds' own primitives no longer hold them."""
    from cad_fixtures import dome_parts

    from fabricate.report.html import highlighted_parts
    from fabricate.report.scene import FAILED_STYLE, part_solids

    parts = dome_parts()
    beams = parts.of_kind("beam")[0]
    bad = [beams.ids[1], parts.of_kind("panel")[0].ids[0]]
    check = {"checks": {"intersections": {"pass": False, "failures": [{"pair": [bad[0], bad[1]]}]},
                        "files": {"pass": True, "failures": [{"id": beams.ids[2]}]}}}
    measures = {"beam_twist": {"pass": False, "enforced": True, "worst": [{"beam": 3, "id": beams.ids[3]}]},
                "closeness": {"pass": False, "enforced": False, "worst": [{"vertex": 0, "id": "N0001"}]}}
    ids = highlighted_parts(check, measures)
    assert ids == [bad[0], bad[1], beams.ids[3]]  # not a passing check's part, not a warning's
    plain, marked = part_solids(parts), part_solids(parts, frozenset(ids))
    red = [m for m in marked if m.name.startswith("failed parts")]
    assert len(red) == 1 and red[0].color == FAILED_STYLE and all(i in red[0].name for i in ids)
    n_plain = {m.name: len(m.positions) for m in plain}
    n_marked = {m.name: len(m.positions) for m in marked}
    per_beam, per_panel = beams.vertices.shape[1], parts.of_kind("panel")[0].vertices.shape[1]
    assert n_marked["steel beams"] == n_plain["steel beams"] - 2 * per_beam
    assert n_marked["glass panels"] == n_plain["glass panels"] - per_panel
    assert len(red[0].positions) == 2 * per_beam + per_panel
    # the red solids are those parts' own corners
    np.testing.assert_allclose(red[0].positions[:per_panel], parts.of_kind("panel")[0].vertices[0])
