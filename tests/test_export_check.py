"""``fabricate check OUTDIR``: every file read back and compared with the bill of materials."""
import dataclasses
import json
import shutil

import pytest
from cad_fixtures import dome_parts, dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.check import check_outputs
from fabricate.app.cli import main
from fabricate.export import write_3mf, write_bom, write_dxf, write_flat, write_step, write_stl, write_svg

FILES = (("model.step", write_step), ("model.stl", write_stl), ("model.3mf", write_3mf),
         ("outlines.dxf", write_dxf), ("outlines.svg", write_svg), ("flat.json", write_flat),
         ("bom.csv", write_bom))


def _write(parts, folder):
    folder.mkdir(parents=True, exist_ok=True)
    for name, fn in FILES:
        fn(parts, folder / name)
    return folder


@pytest.fixture(scope="module")
def parts():
    return dome_parts(6, 3)


@pytest.fixture(scope="module")
def run_dir(parts, tmp_path_factory):
    return _write(parts, tmp_path_factory.mktemp("run") / "out")


def test_a_written_run_passes_every_check(run_dir, parts):
    result = check_outputs(run_dir)
    assert result["pass"], result["failed"]
    c = result["checks"]
    assert c["step"]["solids"] == len(parts) and c["step"]["volume_rel_error_max"] < 1e-9
    assert c["3mf"]["objects"] == len(parts)
    assert c["stl"]["components"] == len(parts) and c["stl"]["genus"] == 1 - len(parts)
    assert c["intersections"]["box_pairs"] > 0 and c["intersections"]["failed"] == 0
    assert c["bearing"]["pairs"] == sum(len([n for n in p.neighbours if n[0] == "B"]) for p in parts.panels)
    assert c["dxf"]["outlines"] == len(parts.panels) + len(parts.beams) and c["dxf"]["audit_errors"] == 0
    assert c["svg"]["pass"]
    assert c["flat"]["pass"] and c["flat"]["against"] == "step" and c["flat"]["parts"] == c["dxf"]["expected"]
    assert c["flat"]["hausdorff_mm_max"] < 1e-6


def test_hub_cap_plates_rebuilt_from_flat_json_equal_their_step_solids(tmp_path):
    """A tube hub's two cap plates are cut from plate: flat.json, the DXF and the SVG carry them, and the
    flat check holds each (outline, thickness, transform) to its STEP solid (volume, Hausdorff 0.01 mm)."""
    tube = {"connection": "hub", "hub": "tube", "radius_mm": 80.0, "wall_mm": 8.0, "cap_mm": 12.0}
    parts = build_parts(dome_structure(n_around=6, k=3), PartSpec(node=tube))
    caps = [i for g in parts.of_kind("node") if g.member.endswith("cap") for i in g.ids]
    assert len(caps) == 2 * len({i.split(".")[0] for i in caps}) > 0
    result = check_outputs(_write(parts, tmp_path / "tube"))
    assert result["pass"], result["failed"]
    c = result["checks"]
    flat_ids = {i for g in json.loads((tmp_path / "tube" / "flat.json").read_text())["groups"] for i in g["ids"]}
    assert set(caps) <= flat_ids and not any(i.endswith(".1") and i[0] == "N" for i in flat_ids)  # no tube
    assert c["flat"]["against"] == "step" and c["flat"]["parts"] == len(parts.panels) + len(parts.beams) + len(caps)
    assert c["flat"]["hausdorff_mm_max"] < 1e-6
    assert c["dxf"]["outlines"] == c["flat"]["parts"] and c["svg"]["groups"] == c["flat"]["parts"]


def test_cli_check_exit_codes(run_dir, tmp_path, capsys):
    assert main(["check", str(run_dir)]) == 0
    assert "all checks passed" in capsys.readouterr().out
    assert main(["check", str(tmp_path / "nothing")]) == 2  # not a run folder: bad input (#15)
    assert main(["check", str(run_dir), "--fast", "--json"]) == 0
    fast = json.loads(capsys.readouterr().out)
    assert fast["mode"] == "fast" and fast["pass"] is True and "scanned" in json.dumps(fast["checks"]["step"])


def test_missing_files_are_reported_as_skipped_not_passed(run_dir, tmp_path):
    partial = tmp_path / "partial"
    shutil.copytree(run_dir, partial)
    (partial / "model.3mf").unlink()
    c = check_outputs(partial)["checks"]
    for name in ("3mf", "stl", "intersections", "bearing"):
        assert c[name]["pass"] is None and "model.3mf" in c[name]["skipped"], c[name]
    assert c["step"]["pass"] and c["dxf"]["pass"]


def test_a_wrong_volume_in_the_bom_fails_the_step_check(run_dir, tmp_path):
    bad = tmp_path / "bad"
    shutil.copytree(run_dir, bad)
    text = (bad / "bom.csv").read_text().splitlines()
    cells = text[1].split(",")
    cells[7] = repr(float(cells[7]) * (1 + 1e-5))
    (bad / "bom.csv").write_text("\n".join([text[0], ",".join(cells)] + text[2:]) + "\n")
    result = check_outputs(bad)
    assert not result["pass"] and "step" in result["failed"]
    assert result["checks"]["step"]["volume_failures"] == [cells[0]]


def test_overlapping_and_floating_parts_fail(parts, tmp_path):
    panels = parts.groups[0]
    lifted = dataclasses.replace(panels, vertices=panels.vertices + 5.0 * panels.normals[:, 1:2, :])
    sunk = dataclasses.replace(panels, vertices=panels.vertices - 5.0 * panels.normals[:, 1:2, :])
    for group, failing in ((lifted, "bearing"), (sunk, "intersections")):
        moved = dataclasses.replace(parts, groups=(group,) + parts.groups[1:])
        folder = tmp_path / failing
        folder.mkdir()
        write_3mf(moved, folder / "model.3mf")
        write_bom(moved, folder / "bom.csv")
        result = check_outputs(folder)
        assert result["failed"] == [failing], result["failed"]


def test_ngon_and_quad_panels_together_pass_the_checks(tmp_path):
    from cad_fixtures import capped_dome_mesh

    from fabricate.offset import offset_structure

    mesh = capped_dome_mesh()
    parts = build_parts(offset_structure(mesh, (0.0, -150.0)), PartSpec(edge="axis"))
    assert sorted(len(g.faces) - 2 for g in parts.of_kind("panel")) == [4, 7]
    result = check_outputs(_write(parts, tmp_path / "capped"))
    assert result["pass"], {k: v for k, v in result["checks"].items() if v.get("pass") is False}
    assert not mesh.notes  # the cap was oriented like its neighbours


def test_without_flat_json_the_dxf_is_checked_against_the_bom(run_dir, tmp_path):
    """A beam's true outline (V ends, ridge) is no face of its solid: without flat.json the CUT
    outlines are held to the BOM's areas, and still pass."""
    import shutil

    copy = tmp_path / "out"
    shutil.copytree(run_dir, copy)
    (copy / "flat.json").unlink()
    result = check_outputs(copy)
    dxf = result["checks"]["dxf"]
    assert dxf["pass"] and dxf["against"] == "bom" and "flat.json" in dxf["note"]
    assert result["checks"]["flat"]["pass"] is None
