"""The fast paths of the DXF and SVG writers, each against the plain computation or an independent reader.

A group's entities are written by one template (read back here by ezdxf, part by part), the stock sheets
after the first by a template (against ezdxf writing every sheet), the bevel labels of a group at once
(against the label of each edge), a bevel line's distance from the outline decided by a bound (against
the full distance table); the drawing data are made once per group.
"""
import dataclasses
import itertools
import re
import xml.etree.ElementTree as ET

import ezdxf
import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.cad.parts import cut_from_sheet
from fabricate.export import dxf as D
from fabricate.export import layout, write_dxf, write_svg
from fabricate.export.flat import _angles, _off_outline, angle_labels, flat_group
from fabricate.export.nesting import sheet_gap

SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture(scope="module")
def parts():
    """Panels, beams and tube hubs: the caps are 24-gons with square edges (no labels, no bevel line)."""
    return build_parts(dome_structure(n_around=6, k=3), PartSpec(node={
        "connection": "hub", "hub": "tube", "radius_mm": 80.0, "wall_mm": 8.0, "cap_mm": 12.0}))


@pytest.fixture(scope="module")
def lay(parts):
    out = layout(parts, sheet=(7000.0, 3000.0), spacing=10.0)
    assert out.sheets > 2 and out.rotated.any() and not out.rotated.all()
    return out


def _normal(text: str) -> str:
    """DXF text without what changes from run to run (GUIDs, Julian dates, ezdxf's time stamps)."""
    text = re.sub(r"\{[0-9A-F-]{36}\}", "GUID", text)
    text = re.sub(r"\n24\d{5}\.\d+", "\nJULIAN", text)
    return re.sub(r"@ \d{4}-\d\d-\d\dT[0-9:.+]+", "@DATE", text)


def test_bevel_labels_of_a_group_are_the_label_of_each_edge():
    rng = np.random.default_rng(5)
    edge = np.array([0.0, -0.0, 0.04999, -0.04999, 0.05, -0.05, 0.05001, 0.95, 1.05, 12.25, -7.75])
    top = np.concatenate([rng.choice(edge, 400), rng.uniform(-30, 30, 400), rng.uniform(-0.1, 0.1, 400)])
    bottom = np.concatenate([rng.choice(edge, 400), -top[400:800] + rng.choice([0, 0.03, -0.04, 0.2], 400),
                             rng.uniform(-0.1, 0.1, 400)])
    top, bottom = top.reshape(60, 20), bottom.reshape(60, 20)
    want = np.vectorize(_angles)(top, bottom)
    got = angle_labels(top, bottom)
    assert got.shape == want.shape and got.tolist() == want.tolist()
    assert {"0"} < set(got.ravel().tolist()) and any("/" in s for s in got.ravel().tolist())


def test_a_bevel_line_off_the_outline_is_found_as_by_the_full_distance_table():
    def full(line, Q):
        return bool(np.linalg.norm(line[:, :, None, :] - Q[:, None, :, :], axis=3).min(axis=2).max() > 1e-6)

    rng = np.random.default_rng(7)
    Q = rng.uniform(-500, 500, (40, 5, 2))
    cases = [Q, Q[:, [2, 3, 4, 0, 1]], Q[:, [0, 1, 1, 2, 3, 4, 4]], rng.uniform(-500, 500, (40, 5, 2))]
    for shift in (2e-6, 5e-7):           # one corner of one later part moved: the bound decides, then the part
        line = Q.copy()
        line[23, 2, 0] += shift
        cases.append(line)
        line = Q.copy()
        line[0, 4, 1] -= shift            # the first part
        cases.append(line)
    found = [_off_outline(line, Q) for line in cases]
    assert found == [full(line, Q) for line in cases]
    assert True in found and False in found


def test_the_sheets_after_the_first_are_written_as_ezdxf_writes_them(lay):
    doc, first = D._skeleton(lay)
    owner = doc.modelspace().block_record_handle
    head, tail = D._assemble(D._written(doc), 0)
    fast = head + D._sheets_text(lay, owner, first, range(1, lay.sheets)) + tail
    doc_all, _ = D._skeleton(lay, every_sheet=True)
    head, tail = D._assemble(D._written(doc_all), 0)
    assert _normal(fast) == _normal(head + tail)
    assert fast.count("  8\nSHEET\n") == 2 * lay.sheets


def test_a_sheet_template_unlike_ezdxf_is_not_used_the_file_stays_the_same(parts, lay, tmp_path, monkeypatch):
    write_dxf(parts, tmp_path / "fast.dxf", lay=lay)
    monkeypatch.setattr(D, "SHEET_TEMPLATE", D.SHEET_TEMPLATE.replace("AcDbText", "AcDbTxtX"))
    write_dxf(parts, tmp_path / "ezdxf.dxf", lay=lay)
    fast, slow = ((tmp_path / f).read_text() for f in ("fast.dxf", "ezdxf.dxf"))
    assert _normal(fast) == _normal(slow) and "AcDbTxtX" not in slow


def _drawn(parts, lay):
    """``{part id: (group, drawing data, index in group, layout row)}``."""
    row = {pid: k for k, pid in enumerate(lay.ids)}
    return {pid: (g, flat_group(g), i, row[pid]) for g in parts.groups if cut_from_sheet(g.kind, g.member)
            for i, pid in enumerate(g.ids) if pid in row}


def test_every_part_entity_reads_back_as_its_drawing_data(parts, lay, tmp_path):
    facts = write_dxf(parts, tmp_path / "o.dxf", lay=lay)
    doc = ezdxf.readfile(str(tmp_path / "o.dxf"))
    assert not doc.audit().has_errors
    ents = [e for e in doc.modelspace() if e.dxf.layer != "SHEET"]
    handles = [int(e.dxf.handle, 16) for e in ents]
    assert handles == list(range(handles[0], handles[0] + len(ents)))
    assert int(doc.header["$HANDSEED"], 16) == handles[-1] + 1 and facts["entities"] == len(ents)
    starts = [j for j, e in enumerate(ents) if e.dxf.layer == "CUT"] + [len(ents)]
    drawn = _drawn(parts, lay)
    assert len(starts) - 1 == len(drawn) == facts["outlines"]
    labels = 0
    for a, b in itertools.pairwise(starts):
        cut, arrow, text, *rest = ents[a:b]
        pid = next(v for code, v in cut.get_xdata(D.APPID) if code == 1000)
        g, fg, i, row = drawn[pid]

        def place(P, g=g, i=i, row=row):
            return D._placed(lay, np.array([row]), g.rect[i:i + 1, 1], P[i:i + 1])[0]

        np.testing.assert_array_equal(np.array(cut.get_points("xy")), place(fg.outline))
        assert cut.closed and arrow.dxf.layer == "ETCH" and not arrow.closed
        np.testing.assert_array_equal(np.array(arrow.get_points("xy")), place(fg.arrow))
        assert (text.dxftype(), text.dxf.layer, text.dxf.text) == ("TEXT", "ETCH", pid)
        at = place(fg.text_at[:, None, :])[0]
        assert tuple(text.dxf.insert)[:2] == tuple(at) == tuple(text.dxf.align_point)[:2]
        assert text.dxf.height == pytest.approx(fg.text_height[i], rel=1e-5)
        nb = len(fg.bevels)
        assert [(e.dxftype(), e.dxf.layer) for e in rest[:nb]] == [("LWPOLYLINE", "BEVEL")] * nb
        for e, line in zip(rest[:nb], fg.bevels):
            np.testing.assert_array_equal(np.array(e.get_points("xy")), place(line))
        keep = fg.angle_text[i] != "0"
        want = [(s, tuple(p)) for s, p in zip(fg.angle_text[i][keep].tolist(), place(fg.angle_at)[keep])]
        got = [(e.dxf.text, tuple(e.dxf.insert)[:2]) for e in rest[nb:]]
        assert got == want and all(e.dxftype() == "TEXT" and e.dxf.layer == "BEVEL" for e in rest[nb:])
        assert all(e.dxf.height == pytest.approx(0.5 * fg.text_height[i], rel=1e-5) for e in rest[nb:])
        labels += len(got)
    assert labels > 0


def test_every_svg_group_is_its_drawing_data(parts, lay, tmp_path):
    write_svg(parts, tmp_path / "o.svg", lay=lay)
    root = ET.parse(tmp_path / "o.svg").getroot()
    groups = {g.get("id"): g for g in root.iter(f"{SVG}g") if g.get("id")}
    drawn = _drawn(parts, lay)
    assert sorted(groups) == sorted(drawn)
    step = lay.size[0] + sheet_gap(lay)

    def points(el):
        return np.array([[float(v) for v in p.split(",")] for p in el.get("points").split()])

    for pid, (g, fg, i, row) in drawn.items():
        el = groups[pid]
        x0, y0 = lay.x[row] + lay.sheet[row] * step, lay.y[row]
        assert el.get("transform") == (f"translate({x0 + g.rect[i, 1]:.4f} {y0:.4f}) rotate(90)" if lay.rotated[row]
                                       else f"translate({x0:.4f} {y0:.4f})")
        cut, *bevels = el.findall(f"{SVG}polygon")
        assert cut.get("class") == "cut" and [b.get("class") for b in bevels] == ["bevel"] * len(fg.bevels)
        for e, line in zip([cut] + bevels, (fg.outline,) + fg.bevels):
            np.testing.assert_allclose(points(e), line[i], atol=0.51e-4, rtol=0)
        np.testing.assert_allclose(points(el.find(f"{SVG}polyline")), fg.arrow[i], atol=0.51e-4, rtol=0)
        text = el.find(f"{SVG}text")
        assert text.text == pid and text.get("font-size") == f"{fg.text_height[i]:.3f}"
        tx, ty = fg.text_at[i]
        assert text.get("transform") == f"translate({tx:.4f} {ty:.4f}) scale(1 -1)"


def test_drawing_data_are_made_once_per_group_object(parts):
    g = next(g for g in parts.groups if cut_from_sheet(g.kind, g.member))
    fg = flat_group(g)
    assert flat_group(g) is fg
    moved = dataclasses.replace(g, flat=g.flat + 1.0)
    other = flat_group(moved)
    assert other is not fg and flat_group(moved) is other
    np.testing.assert_allclose(other.text_at, fg.text_at + 1.0)
