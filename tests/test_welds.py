"""The weld schedule (fabricate.export.welds): joints found on the solids, their type, throat, length, totals."""
import csv
import functools

import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.export.bom import read_bom, write_bom
from fabricate.export.welds import check_weld_schedule, fillet_throat, weld_joints, write_weld_schedule

TUBE = dict(connection="hub", hub="tube", radius_mm=90.0, wall_mm=8.0, cap_mm=12.0)
SECTIONS = {"tee": dict(section="tee", web_mm=10, flange_mm=12, flange_width_mm=140),
            "rhs": dict(section="rhs", web_mm=6, flange_mm=8, flange_width_mm=120)}


@functools.lru_cache(maxsize=None)
def built(section: str):
    return build_parts(dome_structure(n_around=6, k=3), PartSpec(node=TUBE, beam=SECTIONS[section]))


def _by(joints, assembly):
    return [j for j in joints if j["assembly"] == assembly]


def test_fillet_throat_rule():
    assert fillet_throat(10.0) == 7.0 and fillet_throat(6.0) == 4.5 and fillet_throat(4.0) == 3.0
    assert fillet_throat(10.0, 5.0) == 5.0
    np.testing.assert_array_equal(fillet_throat(np.array([12.0, 8.0])), [8.5, 6.0])


def test_tee_seams_are_fillets_along_the_flange_and_ends_weld_all_round():
    parts = built("tee")
    joints = weld_joints(parts)
    flanges = {g.member: g for g in parts.of_kind("beam")}
    for g in parts.of_kind("beam"):
        for i, pid in enumerate(g.ids[:3]):
            if g.member == "web":
                continue
            seam = [j for j in _by(joints, pid.split(".")[0]) if j["where"] == "seam" and pid in j["parts"]]
            assert len(seam) == 1 and seam[0]["weld"] == "fillet" and seam[0]["joint_type"] == "T"
            V = g.vertices[i]                                  # the flange's inner face (0 4 5 1) along the web
            inner = max(np.linalg.norm(V[1] - V[0]), np.linalg.norm(V[5] - V[4]))
            assert seam[0]["length_mm"] == pytest.approx(inner, abs=0.5)
            assert seam[0]["throat_mm"] == 7.0                  # 0.7 x the 10 mm web
    assert "web" in flanges
    b1 = _by(joints, "B0001")
    ends = [j for j in b1 if j["where"].startswith("end")]
    assert [j["where"] for j in ends] == ["end a", "end b"]
    assert all(j["length_mm"] == pytest.approx(2 * (200 + 140)) for j in ends)   # the T's outline
    assert ends[0]["parts"][:3] == ["B0001.1", "B0001.2", "B0001.3"] and ends[0]["parts"][3].endswith(".1")


def test_rhs_seams_are_butt_welds_from_outside_and_caps_weld_round_the_tube():
    parts = built("rhs")
    joints = weld_joints(parts)
    seams = [j for j in _by(joints, "B0001") if j["where"] == "seam"]
    kinds = sorted((j["weld"], j["joint_type"]) for j in seams)
    assert kinds == [("HV", "corner")] * 4 + [("V", "butt")] * 2   # webs on flanges, flange halves on the ridge
    assert {tuple(j["parts"]) for j in seams if j["weld"] == "V"} == {("B0001.3", "B0001.4"), ("B0001.5", "B0001.6")}
    ends = [j for j in _by(joints, "B0001") if j["where"].startswith("end")]
    assert all(j["length_mm"] == pytest.approx(2 * (200 + 120)) for j in ends)
    tube = parts.by_id[next(j["parts"][0] for j in joints if j["where"] == "cap")]
    hub = tube.id.split(".")[0]
    caps = [j for j in _by(joints, hub) if j["where"] == "cap"]
    assert [j["parts"] for j in caps] == [[f"{hub}.1", f"{hub}.2"], [f"{hub}.1", f"{hub}.3"]]
    ring = tube.vertices[:len(tube.vertices) // 4]                # the tube's outside at its lower end
    perimeter = np.linalg.norm(np.roll(ring, -1, axis=0) - ring, axis=1).sum()
    assert all(j["length_mm"] == pytest.approx(perimeter, rel=1e-9) and j["throat_mm"] == 8.0 for j in caps)
    n_tubes = sum(len(g) for g in parts.of_kind("node") if g.member == "tube")
    assert sum(j["where"] == "cap" for j in joints) == 2 * n_tubes


def test_schedule_totals_and_the_check(tmp_path):
    parts = built("rhs")
    facts = write_weld_schedule(parts, tmp_path / "weld_schedule.csv")
    write_bom(parts, tmp_path / "bom.csv")
    bom = read_bom(tmp_path / "bom.csv")
    rows = list(csv.DictReader(open(tmp_path / "weld_schedule.csv", encoding="utf-8")))
    assert rows[-1]["joint"] == "roof total"
    joints = [r for r in rows if r["where"] != "total"]
    assert float(rows[-1]["length_mm"]) == pytest.approx(sum(float(r["length_mm"]) for r in joints), abs=0.05 * len(rows))
    assert facts["length_m"]["total"] == pytest.approx(float(rows[-1]["length_mm"]) * 1e-3, abs=1e-3)
    assert facts["joints"] == len(joints) and facts["assemblies"] >= 30
    result = check_weld_schedule(tmp_path / "weld_schedule.csv", bom)
    assert result["pass"], result["problems"]
    # the two ridge seams left out: the beam's two halves are no longer welded, its total no longer adds up
    drop = {i for i, r in enumerate(rows) if r["joint"] in ("B0002-W5", "B0002-W6")}
    with open(tmp_path / "weld_schedule.csv", "w", encoding="utf-8", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(r for i, r in enumerate(rows) if i not in drop)
    bad = check_weld_schedule(tmp_path / "weld_schedule.csv", bom)
    assert not bad["pass"]
    assert any("beam B0002" in p and "not welded" in p for p in bad["problems"])
    assert any("B0002 total" in p for p in bad["problems"])


def test_fabricate_check_holds_the_weld_schedule_to_the_bom(tmp_path):
    from fabricate.check import check_outputs

    parts = built("tee")
    write_bom(parts, tmp_path / "bom.csv")
    write_weld_schedule(parts, tmp_path / "weld_schedule.csv")
    assert check_outputs(tmp_path)["checks"]["welds"]["pass"] is True
    text = (tmp_path / "weld_schedule.csv").read_text(encoding="utf-8")
    (tmp_path / "weld_schedule.csv").write_text(text.replace("B0003.2", "B9999.2", 1), encoding="utf-8")
    result = check_outputs(tmp_path)["checks"]["welds"]
    assert result["pass"] is False and any("B9999.2" in p for p in result["problems"])
