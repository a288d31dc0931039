"""``fabricate check``: a file the run wrote that is gone fails ("missing"); every FAIL line says why."""
import json
import shutil

import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.check import check_outputs, failure_reasons
from fabricate.check_fast import run_check
from fabricate.app.cli import main
from fabricate.export import write_3mf, write_bom, write_dxf, write_step, write_stl, write_svg

FILES = (("model.step", write_step), ("model.stl", write_stl), ("model.3mf", write_3mf),
         ("outlines.dxf", write_dxf), ("outlines.svg", write_svg), ("bom.csv", write_bom))


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A run folder as `fabricate run` leaves it: the files and report.json listing them."""
    parts = build_parts(dome_structure(n_around=6, k=3), PartSpec())
    folder = tmp_path_factory.mktemp("run") / "out"
    folder.mkdir()
    for name, fn in FILES:
        fn(parts, folder / name)
    files = {p.name: {"bytes": p.stat().st_size} for p in folder.iterdir()}
    (folder / "report.json").write_text(json.dumps({"name": "t", "files": files}))
    return folder


def _copy(run_dir, tmp_path, name):
    out = tmp_path / name
    shutil.copytree(run_dir, out)
    return out


@pytest.mark.parametrize("mode", ["full", "fast"])
def test_a_deleted_file_the_run_wrote_fails_missing(run_dir, tmp_path, mode):
    for gone in ("model.stl", "model.step", "outlines.dxf"):
        d = _copy(run_dir, tmp_path, f"{mode}-{gone}")
        (d / gone).unlink()
        r = run_check(d, mode)
        name = {"model.stl": "stl", "model.step": "step", "outlines.dxf": "dxf"}[gone]
        assert r["pass"] is False and name in r["failed"], r["failed"]
        c = r["checks"][name]
        assert c["pass"] is False and c["missing"] == gone and gone in c["why"][0]


def test_a_file_never_written_is_still_a_skip(run_dir, tmp_path):
    d = _copy(run_dir, tmp_path, "nostl")
    (d / "model.stl").unlink()
    report = json.loads((d / "report.json").read_text())
    del report["files"]["model.stl"]
    (d / "report.json").write_text(json.dumps(report))
    c = check_outputs(d)["checks"]["stl"]
    assert c["pass"] is None and "not written" in c["skipped"]


def test_every_fail_line_says_why(run_dir, tmp_path, capsys):
    d = _copy(run_dir, tmp_path, "bad")
    (d / "model.stl").unlink()
    text = (d / "bom.csv").read_text().splitlines()
    cells = text[1].split(",")
    cells[7] = repr(float(cells[7]) * (1 + 1e-5))  # a volume the STEP and 3MF no longer have
    (d / "bom.csv").write_text("\n".join([text[0], ",".join(cells)] + text[2:]) + "\n")
    assert main(["check", str(d)]) == 4
    lines = [x for x in capsys.readouterr().out.splitlines() if x.startswith("FAIL")]
    assert {x.split()[1] for x in lines} >= {"stl", "step", "3mf"}
    by = {x.split()[1]: x for x in lines}
    assert "model.stl is missing" in by["stl"]
    assert f"volume off the BOM's: {cells[0]}" in by["step"] and f"volume off the BOM's: {cells[0]}" in by["3mf"]


def test_failure_reasons_name_the_flags_and_counts():
    why = failure_reasons({"pass": False, "unit_mm": False, "solids": 3, "bom_rows": 4, "missing": ["P0001"]})
    assert "the unit is not mm" in why and "3 solids for BOM rows 4" in why
    assert any("P0001" in w for w in why)
