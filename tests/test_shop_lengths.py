"""One length per beam in the steel cut list, the NC1 files and the IFC; the NC1 header and contour
fields (grade with its quality, weld preparation, texts never cut, the tube's stock size)."""
import csv
import functools

import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.export import nc1, write_nc1, write_steel_cut_list
from fabricate.export.nc1_read import read_nc1

TUBE = dict(connection="hub", hub="tube", radius_mm=90.0, wall_mm=8.0, cap_mm=12.0)
TEE = dict(section="tee", web_mm=10, flange_mm=12, flange_width_mm=140)


@functools.lru_cache(maxsize=None)
def built():
    return build_parts(dome_structure(n_around=6, k=3), PartSpec(node=TUBE, beam=TEE))


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    out = tmp_path_factory.mktemp("shop")
    write_nc1(built(), out / "nc1", order="a roof whose order name is far longer than a header line holds, twice over")
    write_steel_cut_list(built(), out / "steel.csv")
    with open(out / "steel.csv", newline="", encoding="utf-8") as fh:
        rows = {r["id"]: r for r in csv.DictReader(fh)}
    return out, rows


def test_one_length_per_beam_in_the_cut_list_and_the_nc1(files):
    out, rows = files
    parts = built()
    for uid in ("B0001", "B0007"):
        beam = rows[uid]
        plates = [r for r in rows.values() if r["assembly"] == uid and r["id"] != uid]
        assert [r["member"] for r in plates] == ["web", "top flange +", "top flange -"]
        lengths = []
        for r in plates:
            h = read_nc1(out / "nc1" / f"{r['id']}.nc1")["header"]
            assert h["length"] == pytest.approx(float(r["length_mm"]), abs=0.06)   # the NC1's is the cut list's
            assert h["drawing"] == uid                                           # drawn as its assembly
            lengths.append(h["length"])
        # the beam: its plates' extent along the axis, end to end: at least its longest plate, and (square
        # ends on hubs) within a plate's bevel of it
        assert float(beam["length_mm"]) >= max(lengths) - 0.06
        assert float(beam["length_mm"]) == pytest.approx(max(lengths), abs=1.0)
        # the node-axis to node-axis length along the glass edge is the system length, longer (hubs)
        assert float(beam["system_length_mm"]) > float(beam["length_mm"])
        a, b = parts.mesh.V[parts.mesh.topology.edges[int(beam["edge"])]]
        assert float(beam["system_length_mm"]) == pytest.approx(np.linalg.norm(b - a), abs=0.06)


def test_nc1_contour_carries_the_weld_preparation_and_x_runs_along_the_beam(files):
    out, _ = files
    parts = built()
    g = next(g for g in parts.of_kind("beam") if g.member == "top flange +")
    text = (out / "nc1" / f"{g.ids[0]}.nc1").read_bytes().decode("ascii")
    ak = text.split("AK\r\n")[1].split("SI\r\n")[0].splitlines()
    values = np.array([[float(v) for v in line.split()[-7:]] for line in ak])     # x y r angle1 land1 angle2 land2
    k = g.flat.shape[1]
    assert values.shape == (k + 1, 7)
    np.testing.assert_allclose(values[:k, [3, 5]], np.nan_to_num(g.bevel_deg[0]), atol=6e-4)
    assert np.abs(g.bevel_deg[0]).max() > 1.0                                  # the flanges are bevelled
    # x along the beam: the glass edge (ring edge 0) runs parallel to x
    Q = values[:k, :2]
    d = Q[1] - Q[0]
    assert abs(d[1]) < 1e-3 * abs(d[0])


def test_nc1_header_grade_texts_and_tube_stock_size(files):
    out, _ = files
    parts = built()
    assert parts.spec.steel_grade == "S355J2"
    h = read_nc1(out / "nc1" / "B0001.2.nc1")["header"]
    assert h["grade"] == "S355J2" and h["quantity"] == 1 and h["code"] == "B" and h["profile"] == "PL12"
    for key in ("order", "text1"):
        assert len(h[key]) <= nc1.TEXT_MAX and h[key].startswith("a roof whose") and "~" in h[key]
    assert h["text2"] == "top flange +" and h["text4"] == "assembly B0001"
    assert "twice over" in (out / "nc1" / "B0001.2.nc1").read_text().splitlines()[1]   # whole in the comment
    assert nc1.fit("x" * 70) != nc1.fit("x" * 69 + "y") and nc1.fit("short") == "short"
    t = read_nc1(next((out / "nc1").glob("N*.1.nc1")))["header"]
    assert t["code"] == "RO" and t["profile"] == f"RO{t['height']:g}x8"          # named by its outside diameter
