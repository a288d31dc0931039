"""The glass order (issue 36): positions of identical units, R12 drawings, labels, and its check."""
import csv
import json
import functools

import numpy as np
import pytest

from cad_fixtures import dome_structure

from fabricate.export.glass_delivery import RACK_KG, RACK_UNITS

INSULATED = {"type": "insulated", "outer": {"type": "monolithic", "thickness_mm": 10}, "cavity_mm": 16,
             "inner": {"type": "laminated", "plies_mm": [6, 6], "interlayer_mm": 1.52}, "edge_seal_mm": 14}


@functools.lru_cache(maxsize=None)
def dome_igu():
    from fabricate.cad import PartSpec, build_parts

    return build_parts(dome_structure(n_around=8, k=4), PartSpec(glass=INSULATED))


def leaning_row(glass=None):
    """Four panels whose joints lean out on the left half and in on the right: two shapes, two hands."""
    from optimize.mesh import Mesh

    from fabricate.cad import PartSpec, build_parts
    from fabricate.offset import offset_structure

    top = np.array([0.0, 1350.0, 2400.0, 3450.0, 4800.0])
    V = np.array([[1200.0 * i, 0.0, 0.0] for i in range(5)] + [[x, 1500.0, 0.0] for x in top])
    F = [[i, i + 1, i + 6, i + 5] for i in range(4)]
    return build_parts(offset_structure(Mesh(V, F), (0.0, -200.0)),
                       PartSpec(glass=glass))


def _rows(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def test_one_row_per_position_with_every_field(tmp_path):
    from fabricate.export import write_glass_order
    from fabricate.export.check_glass_order import check_glass_order

    parts = dome_igu()
    facts = write_glass_order(parts, tmp_path / "glass_order.csv")
    rows = _rows(tmp_path / "glass_order.csv")
    assert facts["positions"] == len(rows) == 3 and facts["units"] == 24             # one shape per ring
    assert sorted(u for r in rows for u in r["units"].split()) == sorted(f"P{i + 1:04d}" for i in range(24))
    r = rows[0]
    assert int(r["quantity"]) == 8 and r["hand"] == "" and r["plies"] == "3"
    assert (r["ply1_treatment"], r["ply1_standard"], r["ply1_coatings"]) == ("toughened-heat-soaked", "EN 14179-1",
                                                                            "#2 solar-control")
    assert r["ply3_treatment"] == "heat-strengthened" and r["ply2_edge_work"] == "smooth-ground (KGN)"
    assert (r["gas"], r["gas_fill_pct"], r["spacer"], r["spacer_colour"], r["secondary_seal"]) == (
        "argon", "90", "warm-edge", "black", "silicone")
    assert "EN 1279-5" in r["standards"] and r["label_text"].endswith("#1 OUTSIDE")
    assert float(r["blank_w_mm"]) >= max(float(r[f"ply{k}_blank_w_mm"]) for k in (1, 2, 3))
    labels = _rows(tmp_path / "glass_order" / "labels.csv")
    assert sorted(int(x["install_seq"]) for x in labels) == list(range(1, 25))
    assert all(x["position"] in {r["position"] for r in rows} for x in labels)
    per_rack = {}
    for x in labels:
        per_rack.setdefault(x["rack"], []).append(float(x["weight_kg"]))
    assert all(len(w) <= RACK_UNITS and (sum(w) <= RACK_KG or len(w) == 1) for w in per_rack.values())
    assert check_glass_order(parts, tmp_path)["pass"]


@pytest.mark.parametrize("glass", [None, {"type": "laminated", "plies_mm": [8, 8]}])
def test_mirror_images_are_positions_of_their_own(tmp_path, glass):
    from fabricate.export import write_glass_order
    from fabricate.export.check_glass_order import check_glass_order

    parts = leaning_row(glass)
    write_glass_order(parts, tmp_path / "glass_order.csv")
    rows = {r["position"]: r for r in _rows(tmp_path / "glass_order.csv")}
    assert sorted(rows) == ["G001A", "G001B", "G002A", "G002B"]
    assert rows["G001A"]["units"] == "P0001" and rows["G001B"]["units"] == "P0004"
    n = int(rows["G001A"]["plies"])
    assert all(float(r[f"ply{k}_blank_w_mm"]) > 1000.0 for r in rows.values() for k in range(1, n + 1))
    assert check_glass_order(parts, tmp_path)["pass"]
    a, b = rows["G001A"]["edge_lengths_mm"].split(), rows["G001B"]["edge_lengths_mm"].split()
    assert b == a[::-1] and a != b                                                  # the mirror, edges run back


def test_the_drawings_are_r12_with_the_outline_alone_on_its_layer(tmp_path):
    import ezdxf

    from fabricate.export import write_glass_order

    parts = dome_igu()
    write_glass_order(parts, tmp_path / "glass_order.csv")
    doc = ezdxf.readfile(str(tmp_path / "glass_order" / "G001.dxf"))
    assert doc.dxfversion == "AC1009"                                                # R12
    outline = [e for e in doc.modelspace() if e.dxf.layer == "OUTLINE"]
    assert len(outline) == 1 and outline[0].dxftype() == "POLYLINE" and outline[0].is_closed
    P = np.array([(v.dxf.location[0], v.dxf.location[1]) for v in outline[0].vertices])
    flat = parts.by_id["P0001.1"].flat                                              # the outer ply's cut outline
    assert sorted(np.linalg.norm(np.roll(P, -1, 0) - P, axis=1)) == pytest.approx(
        sorted(np.linalg.norm(np.roll(flat, -1, 0) - flat, axis=1)), abs=1e-6)
    texts = {e.dxf.text for e in doc.modelspace().query("TEXT")}
    assert {"E1", "E2", "E3", "E4", "1"} <= texts
    assert {e.dxf.layer for e in doc.modelspace()} == {"OUTLINE", "PLY2", "PLY3", "BEARING", "DIMENSIONS", "TEXT"}
    svg = (tmp_path / "glass_order" / "G001.svg").read_text()
    assert svg.startswith("<svg") and "G001" in svg


def test_the_check_finds_a_unit_twice_a_moved_corner_and_a_short_blank(tmp_path):
    import ezdxf

    from fabricate.export import write_glass_order
    from fabricate.export.check_glass_order import check_glass_order

    parts = dome_igu()
    write_glass_order(parts, tmp_path / "glass_order.csv")
    path = tmp_path / "glass_order.csv"
    rows = _rows(path)
    rows[1]["units"] += " P0001"                                                     # in two positions
    rows[1]["quantity"] = str(int(rows[1]["quantity"]) + 1)
    rows[2]["ply2_blank_w_mm"] = f"{float(rows[2]['ply2_blank_w_mm']) - 3:.1f}"     # 3 mm short
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    dxf = tmp_path / "glass_order" / "G001.dxf"
    doc = ezdxf.readfile(str(dxf))
    poly = next(e for e in doc.modelspace() if e.dxf.layer == "OUTLINE")
    v = poly.vertices[2]
    v.dxf.location = (v.dxf.location[0] + 2.5, v.dxf.location[1])                   # a corner 2.5 mm out
    doc.saveas(str(dxf))
    result = check_glass_order(parts, tmp_path)
    text = "\n".join(result["problems"])
    assert not result["pass"]
    assert "unit P0001 in positions G001 and G002" in text
    assert "from the drawing of position G001" in text and "ply 2: blank" in text


def _run_folder(parts, folder):
    """A run folder as the library writes it: the BOM, the flat data, the 3MF and the glass order."""
    from fabricate.export import write_3mf, write_bom, write_flat, write_glass_order

    folder.mkdir(parents=True, exist_ok=True)
    write_bom(parts, folder / "bom.csv")
    write_flat(parts, folder / "flat.json")
    write_3mf(parts, folder / "model.3mf")
    write_glass_order(parts, folder / "glass_order.csv")
    return folder


def _rewrite(path, rows):
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


@pytest.mark.parametrize("parts", [dome_igu, leaning_row, lambda: leaning_row({"type": "laminated",
                                                                              "plies_mm": [8, 8]})])
def test_the_flat_data_gives_the_units_the_parts_give(tmp_path, parts):
    """The standalone check's reference, read from flat.json alone, is the in-run check's (the parts')."""
    from fabricate.export import write_flat
    from fabricate.export.check_glass_order import flat_reference, unit_reference

    p = parts()
    write_flat(p, tmp_path / "flat.json")
    a, b = unit_reference(p), flat_reference(tmp_path / "flat.json")
    assert a["ids"] == b["ids"] and len(a["ids"]) == len(p.panels) // len(p.spec.glass.solids())
    for u in a["ids"]:
        np.testing.assert_allclose(b["rings"][u], a["rings"][u], atol=1e-6)
        np.testing.assert_array_equal(b["blanks"][u], a["blanks"][u])


def test_fabricate_check_holds_the_order_to_the_files(tmp_path, capsys):
    """#36 item 5: `fabricate check` reads glass_order.csv back against flat.json: a unit moved to a
    position of another shape, or deleted, fails it (exit 4) naming the unit and the position."""
    from fabricate.app.cli import main

    out = _run_folder(dome_igu(), tmp_path / "run")
    assert main(["check", str(out)]) == 0
    assert "glass_order" in capsys.readouterr().out
    rows = _rows(out / "glass_order.csv")
    moved = rows[0]["units"].split()[0]
    rows[0]["units"] = " ".join(rows[0]["units"].split()[1:])
    rows[0]["quantity"] = str(int(rows[0]["quantity"]) - 1)
    rows[1]["units"] += f" {moved}"
    rows[1]["quantity"] = str(int(rows[1]["quantity"]) + 1)
    _rewrite(out / "glass_order.csv", rows)
    assert main(["check", str(out)]) == 4
    text = capsys.readouterr().out
    assert f"unit {moved} is " in text and f"from the drawing of position {rows[1]['position']}" in text
    assert "FAIL glass_order" in text and "FAILED: glass_order" in text
    deleted = rows[1]["units"].split()[0]                                       # and one unit deleted
    rows[1]["units"] = " ".join(u for u in rows[1]["units"].split() if u not in (deleted, moved))
    rows[1]["quantity"] = str(len(rows[1]["units"].split()))
    _rewrite(out / "glass_order.csv", rows)
    assert main(["check", str(out), "--json"]) == 4
    result = json.loads(capsys.readouterr().out)["checks"]["glass_order"]
    assert result["pass"] is False and result["against"] == "flat.json"
    assert any("in no position" in p and deleted in p and moved in p for p in result["problems"])
    assert not any("from the drawing" in p for p in result["problems"])
