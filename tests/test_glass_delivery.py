"""The glass order's labels (a QR code per unit) and its delivery: racks by zone (issue 36 item 4)."""
import csv
import re
from collections import Counter

import numpy as np
import pytest
from test_glass_order import dome_igu, leaning_row

from fabricate.export.glass_delivery import RACK_KG, sequence

RUN = re.compile(r"M(\d+),(\d+)h(\d+)v1h-(\d+)z")


def _rows(path):
    with open(path, newline="", encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def _labels(folder):
    """Per label in the sheets: (unit, position, sheet, text, the QR path's transform and data, mark)."""
    out = []
    for sheet in sorted(folder.glob("labels_*.svg")):  # one sheet or a few per rack
        svg = sheet.read_text(encoding="utf-8")
        assert svg.startswith("<svg") and 'width="210mm" height="297mm"' in svg
        for g in re.findall(r'<g class="label".*?</g></g>', svg, flags=re.S):
            unit = re.search(r'data-unit="([^"]*)"', g).group(1)
            position = re.search(r'data-position="([^"]*)"', g).group(1)
            qr = re.findall(r'<path class="qr" transform="translate\(([\d.]+),([\d.]+)\) scale\(([\d.]+)\)" '
                            r'd="([^"]*)"', g)
            out.append({"unit": unit, "position": position, "sheet": sheet.name, "qr": qr,
                        "texts": re.findall(r">([^<>]+)</text>", g), "mark": re.findall(r'<g class="orientation">', g)})
    return out


def test_every_unit_has_one_label_with_its_qr_code_and_orientation_mark(tmp_path):
    import segno

    from fabricate.export import write_glass_order

    write_glass_order(dome_igu(), tmp_path / "glass_order.csv")
    order = _rows(tmp_path / "glass_order.csv")
    position = {u: r["position"] for r in order for u in r["units"].split()}
    labels = _labels(tmp_path / "glass_order")
    assert Counter(lab["unit"] for lab in labels) == Counter(list(position))       # exactly one label each
    racks = {r["id"]: r["rack"] for r in _rows(tmp_path / "glass_order" / "labels.csv")}
    cells = set()
    for lab in labels:  # a few dozen labels
        u = lab["unit"]
        assert lab["position"] == position[u] and lab["sheet"] == f"labels_{racks[u]}.svg"
        assert u in lab["texts"] and f"Pos {position[u]}" in lab["texts"] and "#1 OUTSIDE" in lab["texts"]
        assert lab["mark"] and "1" in lab["texts"] and "E1" in lab["texts"]        # corner 1, the arrow along E1
        (x, y, m, d), = lab["qr"]
        drawn = set()
        for c, r, w, back in RUN.findall(d):  # the runs of dark modules
            assert w == back
            drawn |= {(int(r), int(c) + j) for j in range(int(w))}
        assert len("".join(RUN.findall(d)[0])) and RUN.sub("", d) == ""          # nothing else in the path
        matrix = segno.make_qr(u, error="m").matrix
        assert drawn == {(r, c) for r, row in enumerate(matrix) for c, v in enumerate(row) if v}
        # the symbol with its 4-module quiet zone inside one 70 x 37 mm label of the A4 sheet's 3 x 8
        x, y, m, n = float(x), float(y), float(m), len(matrix)
        lo, hi = np.array([x - 4 * m, y - 4 * m]), np.array([x + (n + 4) * m, y + (n + 4) * m])
        cell = np.floor((lo - [0.0, 0.5]) / [70.0, 37.0]).astype(int)
        assert np.all(hi <= cell * [70.0, 37.0] + [0.0, 0.5] + [70.0, 37.0] + 1e-9) and np.all(lo >= 0.0)
        assert 0 <= cell[0] < 3 and 0 <= cell[1] < 8 and (lab["sheet"], *cell) not in cells
        cells.add((lab["sheet"], *cell))
        assert m >= 0.9                                                             # modules a phone reads


def test_racks_by_zone_in_install_order_within_the_rack_weight(tmp_path):
    from fabricate.export import write_glass_order

    parts = dome_igu()
    for limit, zone_mm in ((RACK_KG, 1e5), (700.0, 3000.0)):  # the default, and a light rack in short zones
        folder = tmp_path / f"{limit:g}"
        folder.mkdir()
        facts = write_glass_order(parts, folder / "glass_order.csv", rack_kg=limit, zone_mm=zone_mm)
        labels = {r["id"]: r for r in _rows(folder / "glass_order" / "labels.csv")}
        racks = _rows(folder / "glass_order" / "racks.csv")
        assert len(racks) == facts["racks"] and facts["heaviest_rack_kg"] <= limit
        listed = [u for r in racks for u in r["unit_ids"].split()]
        assert sorted(listed) == sorted(labels)                                     # every unit on one rack
        seq = [int(labels[u]["install_seq"]) for u in listed]
        assert seq == list(range(1, len(labels) + 1))                               # racks in install order, front first
        for r in racks:  # a few racks
            units = r["unit_ids"].split()
            w = [float(labels[u]["weight_kg"]) for u in units]
            assert float(r["weight_kg"]) == pytest.approx(sum(w), abs=0.1 * len(w))
            assert sum(w) <= limit + 0.05 * len(w) and float(r["max_weight_kg"]) == limit
            assert {labels[u]["rack"] for u in units} == {r["rack"]} and [int(labels[u]["rack_slot"]) for u in units] \
                == list(range(1, len(units) + 1))
            assert {labels[u]["zone"] for u in units} == {r["zone"]}                 # a rack never spans zones
            assert (int(r["install_from"]), int(r["install_to"])) == (seq[listed.index(units[0])],
                                                                      seq[listed.index(units[-1])])
        zones = [int(r["zone"]) for r in racks]
        assert zones == sorted(zones) and zones[0] == 1
        if zone_mm < 1e5:
            assert zones[-1] > 1 and len(racks) > facts["zones"]
    assert len(_rows(tmp_path / "700" / "glass_order" / "racks.csv")) > len(_rows(tmp_path / "1500" / "glass_order"
                                                                               / "racks.csv"))


def test_a_unit_over_the_rack_limit_goes_alone_marked(tmp_path):
    from fabricate.export import write_glass_order

    parts = leaning_row({"type": "laminated", "plies_mm": [8, 8]})
    write_glass_order(parts, tmp_path / "glass_order.csv", rack_kg=1.0)
    racks = _rows(tmp_path / "glass_order" / "racks.csv")
    assert len(racks) == 4 and all(r["units"] == "1" and r["over_limit"] == "yes" for r in racks)
    labels = _rows(tmp_path / "glass_order" / "labels.csv")
    x = [float(r["x_mm"]) for r in sorted(labels, key=lambda r: int(r["install_seq"]))]
    assert x == sorted(x) or x == sorted(x)[::-1]                                   # along the row, end to end


def test_the_sequence_snakes_row_by_row_and_zones_follow_the_long_axis():
    """A 10 x 3 grid of 1 m units, 100 kg each, the long axis along x: rows of 3 across it, each the
    reverse of the last; zones 4 m long; racks of at most 4 (450 kg) inside one zone."""
    rng = np.random.default_rng(3)
    X, Y = np.meshgrid(np.arange(10) * 1000.0, np.arange(3) * 1000.0)
    C = np.stack([X.ravel(), Y.ravel(), np.zeros(30)], axis=1)
    perm = rng.permutation(30)
    s = sequence(C[perm], np.full(30, 100.0), 1000.0, rack_kg=450.0, zone_mm=4000.0)
    P = C[perm][np.argsort(s["seq"])]
    assert np.all(np.linalg.norm(np.diff(P, axis=0), axis=1) <= 1000.0 + 1e-6)    # each next unit a neighbour
    along = np.abs(P[:, 0] - P[0, 0])
    assert np.all(np.diff(along) >= -1e-9)                                          # row after row along x
    zone = s["zone"][np.argsort(s["seq"])]
    np.testing.assert_array_equal(zone, np.floor(along / 4000.0 + 1e-9).astype(int) + 1)
    rack = s["rack"][np.argsort(s["seq"])]
    assert np.all(np.diff(rack) >= 0) and rack.max() == 3 + 3 + 2                   # 12, 12, 6 units by zone
    for r in np.unique(rack):  # the racks
        assert np.sum(rack == r) <= 4 and len(set(zone[rack == r])) == 1
    with pytest.raises(ValueError, match="rack_kg"):
        sequence(C, np.ones(30), 1000.0, rack_kg=0.0)


def test_the_check_finds_a_unit_off_its_rack_an_overloaded_rack_and_a_lost_label(tmp_path):
    import re

    from fabricate.export import write_glass_order
    from fabricate.export.check_glass_order import check_glass_order

    parts = dome_igu()
    write_glass_order(parts, tmp_path / "glass_order.csv")
    assert check_glass_order(parts, tmp_path)["pass"]
    folder = tmp_path / "glass_order"
    racks = _rows(folder / "racks.csv")
    dropped = racks[0]["unit_ids"].split()[-1]
    racks[0]["unit_ids"] = " ".join(racks[0]["unit_ids"].split()[:-1])            # a unit on no rack
    racks[1]["weight_kg"] = f"{float(racks[1]['max_weight_kg']) + 10:.1f}"          # over the limit
    with open(folder / "racks.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(racks[0]))
        w.writeheader()
        w.writerows(racks)
    sheet = folder / racks[2]["label_sheet"]
    svg = sheet.read_text(encoding="utf-8")
    lost = re.search(r'<g class="label" data-unit="([^"]*)"', svg).group(1)
    sheet.write_text(re.sub(r'<g class="label" data-unit="' + lost + r'".*?</g></g>', "", svg, flags=re.S),
                     encoding="utf-8")
    problems = "\n".join(check_glass_order(parts, tmp_path)["problems"])
    assert f"1 unit(s) with no row: {dropped}" in problems
    assert f"rack {racks[1]['rack']}: {float(racks[1]['weight_kg']):.1f} kg over its limit" in problems
    assert f"1 unit(s) with no label on the label sheets: {lost}" in problems
