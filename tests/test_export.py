"""Exporters: STEP (direct and OCC engines, read back by OpenCASCADE and the text reader), STL, 3MF, DXF, SVG, BOM."""
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from cad_fixtures import dome_mesh, dome_parts

from fabricate.cad import COLOURS, PartSpec, build_parts
from fabricate.export import layout, write_3mf, write_bom, write_dxf, write_step, write_stl, write_svg
from fabricate.export.bom import read_bom
from fabricate.export.brep import solid_facts
from fabricate.export.dxf import read_outlines
from fabricate.export.step_read import read_step
from fabricate.export.stl import read_stl
from fabricate.export.threemf import read_3mf
from fabricate.export.verify import face_polygons, match_outline
from fabricate.offset import offset_structure
from optimize.errors import ConfigError


@pytest.fixture(scope="module")
def parts():
    return dome_parts(6, 3)


@pytest.fixture(scope="module")
def step_file(parts, tmp_path_factory):
    path = tmp_path_factory.mktemp("step") / "model.step"
    facts = write_step(parts, path)
    return path, facts


def _volumes(parts):
    return {p.id: p.volume_mm3 for p in parts}


def test_direct_step_reads_back_valid_named_and_exact(parts, step_file):
    path, facts = step_file
    assert facts["parts"] == len(parts) and not facts["pcurves"] and facts["engine"] == "direct"
    solids, info = read_step(path)
    assert [n for n, _ in solids] == [p.id for p in parts]
    expected = _volumes(parts)
    for name, shape in solids:
        f = solid_facts(shape)
        assert f["valid"] and f["solids"] == 1
        assert f["volume_mm3"] == pytest.approx(expected[name], rel=1e-9)
    assert "SI_UNIT(.MILLI.,.METRE.)" in path.read_text()[:20000]
    for p in parts:  # coloured by kind
        np.testing.assert_allclose(info["colours"][p.id], COLOURS[p.kind], atol=2e-3)
    assert not list(path.parent.glob(".*part"))  # atomic: no temporary file left


def test_occ_engine_writes_the_same_solids(parts, tmp_path):
    path = tmp_path / "occ.step"
    facts = write_step(parts, path, engine="occ")
    assert facts["engine"] == "occ" and facts["pcurves"]
    solids, info = read_step(path)
    expected = _volumes(parts)
    assert sorted(n for n, _ in solids) == sorted(expected)
    for p in parts:
        np.testing.assert_allclose(info["colours"][p.id], COLOURS[p.kind], atol=2e-3)
    for name, shape in solids:
        f = solid_facts(shape)
        assert f["valid"] and f["volume_mm3"] == pytest.approx(expected[name], rel=1e-9)


def test_the_step_text_reader_finds_the_names_and_volumes(parts, step_file):
    """A reader that is not OpenCASCADE (gmsh, used here before, reads STEP through OpenCASCADE too):
    the project's own STEP text reader (fabricate.export.step_text) against the analytic volumes."""
    from fabricate.export.step_text import read_step_text

    solids, facts = read_step_text(step_file[0])
    expected = _volumes(parts)
    assert facts["unit_mm"] and facts["complete"] and list(solids) == [p.id for p in parts]
    for name, solid in solids.items():
        assert solid["volume_mm3"] == pytest.approx(expected[name], rel=1e-9)


def test_stl_is_the_same_triangles_and_records_the_origin(parts, tmp_path):
    facts = write_stl(parts, tmp_path / "m.stl")
    assert facts["manifold"]["status"] == "NoError" and facts["manifold"]["components"] == len(parts)
    assert facts["manifold"]["genus"] == 1 - len(parts)
    assert facts["manifold"]["volume_rel_error"] < 1e-12
    P, header = read_stl(tmp_path / "m.stl")
    assert len(P) == facts["triangles"] and header["parts"] == len(parts)
    np.testing.assert_array_equal(header["origin"], np.zeros(3))
    A = P.astype(float)
    vol = np.einsum("ij,ij->i", A[:, 0], np.cross(A[:, 1], A[:, 2])).sum() / 6
    assert vol == pytest.approx(sum(_volumes(parts).values()), rel=1e-5)


def test_far_from_origin_model_is_moved_to_a_local_origin(tmp_path):
    mesh = dome_mesh(n_around=6, k=3)
    far = mesh.with_vertices(mesh.V + [3.2e8, 5.1e9, 120.0])  # georeferenced mm
    parts = build_parts(offset_structure(far, (0.0, -200.0)), PartSpec())
    facts = write_stl(parts, tmp_path / "far.stl")
    assert np.linalg.norm(facts["origin_mm"]) > 1e9
    P, header = read_stl(tmp_path / "far.stl")
    np.testing.assert_allclose(header["origin"], facts["origin_mm"])
    assert np.abs(P).max() < 2e4  # coordinates are local
    A = P.astype(float)
    vol = np.einsum("ij,ij->i", A[:, 0], np.cross(A[:, 1], A[:, 2])).sum() / 6
    assert vol == pytest.approx(sum(_volumes(parts).values()), rel=1e-5)


def test_3mf_round_trip_names_and_vertices(parts, tmp_path):
    facts = write_3mf(parts, tmp_path / "m.3mf")
    objects = read_3mf(tmp_path / "m.3mf")
    assert facts["objects"] == len(objects) == len(parts)
    for p in parts:
        V, T = objects[p.id]
        np.testing.assert_allclose(V, p.vertices, rtol=1e-11, atol=1e-8)
        assert len(T) == sum(len(f) - 2 for f in p.faces)


def test_dxf_outlines_are_the_flat_outlines_and_the_step_faces_lie_in_them(parts, step_file, tmp_path):
    facts = write_dxf(parts, tmp_path / "o.dxf")
    assert facts["outlines"] == len(parts.panels) + len(parts.beams) and "audit clean" in facts["audit"]
    outlines, info = read_outlines(tmp_path / "o.dxf")
    assert info["audit_errors"] == 0 and info["units"] == 4 and info["texts"] == facts["outlines"]
    assert sorted(outlines) == sorted(p.id for p in parts.panels + parts.beams)
    solids = dict(read_step(step_file[0])[0])
    for pid, Q in outlines.items():
        part = parts.by_id[pid]
        flat3 = np.concatenate([part.flat, np.zeros((len(part.flat), 1))], axis=1)
        fi, rel, err = match_outline(Q, [flat3])
        assert fi == 0 and rel < 1e-12 and err < 1e-9
        # every corner of the STEP solid, seen in the part frame, lies inside the cut outline
        M = part.transform
        X = np.concatenate(face_polygons(solids[pid]))
        local = (X - M[:3, 3]) @ M[:3, :3]
        F = part.flat
        E = np.roll(F, -1, axis=0) - F
        cross = E[:, None, 0] * (local[None, :, 1] - F[:, None, 1]) - E[:, None, 1] * (local[None, :, 0] - F[:, None, 0])
        assert (cross / np.linalg.norm(E, axis=1)[:, None]).min() > -1e-6


@pytest.mark.parametrize("sheet", [(7000.0, 3000.0), (3000.0, 7000.0)])
def test_nesting_packs_parts_on_sheets_without_overlap(parts, sheet):
    lay = layout(parts, sheet=sheet, spacing=15.0)
    assert "rectpack" in lay.algorithm
    W, H = lay.size
    assert lay.sheets >= 1 and np.all((lay.utilisation > 0) & (lay.utilisation <= 1))
    rect = np.array([parts.by_id[i].rect for i in lay.ids])
    w = np.where(lay.rotated, rect[:, 1], rect[:, 0])
    h = np.where(lay.rotated, rect[:, 0], rect[:, 1])
    assert np.all(lay.x >= 15 - 1e-9) and np.all(lay.y >= 15 - 1e-9)
    assert np.all(lay.x + w <= W - 15 + 1e-9) and np.all(lay.y + h <= H - 15 + 1e-9)
    for s in range(lay.sheets):  # pairwise: rectangles plus spacing never overlap
        i = np.nonzero(lay.sheet == s)[0]
        x0, y0, x1, y1 = lay.x[i], lay.y[i], lay.x[i] + w[i], lay.y[i] + h[i]
        apart = ((x1[:, None] + 15 <= x0[None, :] + 1e-9) | (x1[None, :] + 15 <= x0[:, None] + 1e-9)
                 | (y1[:, None] + 15 <= y0[None, :] + 1e-9) | (y1[None, :] + 15 <= y0[:, None] + 1e-9))
        assert np.all(apart | np.eye(len(i), dtype=bool))
    assert np.all(lay.rotated[rect[:, 0] > W - 30])  # too long for the sheet: turned
    area = sum(parts.by_id[i].area_mm2 for i in lay.ids)
    assert lay.utilisation.sum() * W * H == pytest.approx(area)
    with pytest.raises(ConfigError, match="does not fit"):
        layout(parts, sheet=(500.0, 400.0))


def test_nesting_keeps_the_kerf_and_turns_no_part_when_rotation_is_off(parts):
    lay = layout(parts, sheet=(7000.0, 3000.0), spacing=20.0, kerf=4.0, rotation=False)
    assert not lay.rotated.any() and lay.facts()["kerf_mm"] == 4.0
    rect = np.array([parts.by_id[i].rect for i in lay.ids])
    for s in range(lay.sheets):
        i = np.nonzero(lay.sheet == s)[0]
        x0, y0, x1, y1 = lay.x[i], lay.y[i], lay.x[i] + rect[i, 0], lay.y[i] + rect[i, 1]
        apart = ((x1[:, None] + 4 <= x0[None, :] + 1e-9) | (x1[None, :] + 4 <= x0[:, None] + 1e-9)
                 | (y1[:, None] + 4 <= y0[None, :] + 1e-9) | (y1[None, :] + 4 <= y0[:, None] + 1e-9))
        assert np.all(apart | np.eye(len(i), dtype=bool))
    assert [f["id"] for f in lay.facts()["per_sheet"]][:1] == ["S-S01"]
    with pytest.raises(ConfigError, match="rotation not allowed"):
        layout(parts, sheet=(3000.0, 7000.0), rotation=False)


def test_svg_has_one_group_per_flat_part(parts, tmp_path):
    facts = write_svg(parts, tmp_path / "o.svg", sheet=(7000.0, 3000.0))
    root = ET.parse(tmp_path / "o.svg").getroot()
    ids = [g.get("id") for g in root.iter("{http://www.w3.org/2000/svg}g") if g.get("id")]
    assert sorted(ids) == sorted(p.id for p in parts.panels + parts.beams)
    assert facts["layout"]["nested"] and root.get("width").endswith("mm")


def test_bom_has_one_row_per_solid_with_exact_volumes(parts, tmp_path):
    facts = write_bom(parts, tmp_path / "bom.csv")
    rows = read_bom(tmp_path / "bom.csv")
    assert facts["rows"] == len(rows) == len(parts)
    for r in rows:
        p = parts.by_id[r["id"]]
        assert float(r["volume_mm3"]) == p.volume_mm3 and r["kind"] == p.kind
        density = parts.spec.density(p.kind)
        assert float(r["weight_kg"]) == pytest.approx(p.volume_mm3 * density * 1e-9, abs=1e-3)
        assert r["neighbours"].split() == list(p.neighbours)
    panel = next(r for r in rows if r["kind"] == "panel")
    assert len(panel["mesh_vertices"].split()) == 4


def test_lib3mf_reads_the_3mf_strictly(parts, tmp_path):
    import lib3mf  # installed with build123d: an independent 3MF reader

    write_3mf(parts, tmp_path / "m.3mf")
    model = lib3mf.get_wrapper().CreateModel()
    reader = model.QueryReader("3mf")
    reader.SetStrictModeActive(True)
    reader.ReadFromFile(str(tmp_path / "m.3mf"))
    assert reader.GetWarningCount() == 0
    it, names = model.GetMeshObjects(), []
    while it.MoveNext():
        obj = it.GetCurrentMeshObject()
        assert obj.IsManifoldAndOriented()
        names.append(obj.GetName())
    assert names == [p.id for p in parts]
