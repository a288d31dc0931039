"""JSON files read back from a folder someone may have changed (run marker, owner record, report.json,
flat.json, a GLB's document): text nested deeper than Python's JSON reader follows (a few hundred bytes
of ``[[[[``) is bad input like any other unreadable file, never an internal error."""
import json
import shutil

import pytest
from _pipeline_fixtures import tiny_config
from cad_fixtures import dome_structure

from fabricate.app.cli import main
from fabricate.app.pipeline import run_pipeline
from fabricate.app.runfolder import MARKER, _holder, read_marker
from fabricate.cad import PartSpec, build_parts
from fabricate.export import write_bom, write_dxf, write_flat, write_step
from fabricate.report.glb import read_glb
from optimize import jsontext
from optimize.atomic import PART_OWNER, read_owner
from optimize.errors import ConfigError

DEEP = "[" * 100_000 + "]" * 100_000


def test_json_nested_too_deep_is_a_value_error_and_json_is_json():
    with pytest.raises(RecursionError):
        json.loads(DEEP)                            # the standard reader: not a ValueError
    with pytest.raises(ValueError, match="nested deeper than the reader follows"):
        jsontext.loads(DEEP)
    with pytest.raises(ValueError):
        jsontext.loads("{")
    assert jsontext.loads('{"a": [1, 2.5, null]}') == {"a": [1, 2.5, None]}


def test_records_nested_too_deep_read_as_unreadable(tmp_path):
    for name in (MARKER, PART_OWNER):
        (tmp_path / name).write_text(DEEP)
    assert read_marker(tmp_path) is None and read_owner(tmp_path) is None
    assert _holder(tmp_path / PART_OWNER) == "a process that just started"
    doc = DEEP.encode()
    glb = b"glTF" + (2).to_bytes(4, "little") + (20 + len(doc)).to_bytes(4, "little")
    glb += len(doc).to_bytes(4, "little") + b"JSON" + doc
    with pytest.raises(ValueError, match="nested deeper"):
        read_glb(glb)


def test_a_folder_whose_marker_is_nested_too_deep_is_not_replaced(tmp_path):
    mine = tmp_path / "out" / "tiny"
    mine.mkdir(parents=True)
    (mine / MARKER).write_text(DEEP)
    with pytest.raises(ConfigError, match="exists and is not a run folder of conical-fab") as info:
        run_pipeline(tiny_config(tmp_path), tmp_path / "out", force=True)
    assert info.value.exit_code == 2 and (mine / MARKER).read_text() == DEEP


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    parts = build_parts(dome_structure(n_around=6, k=3), PartSpec())
    folder = tmp_path_factory.mktemp("run")
    for name, fn in (("model.step", write_step), ("bom.csv", write_bom), ("flat.json", write_flat),
                     ("outlines.dxf", write_dxf)):
        fn(parts, folder / name)
    return folder


def test_check_of_a_folder_with_json_nested_too_deep(run_dir, tmp_path, capsys):
    d = tmp_path / "out"
    shutil.copytree(run_dir, d)
    assert main(["check", str(d)]) == 0
    capsys.readouterr()
    (d / "report.json").write_text(DEEP)               # a report that does not read fails the files row
    assert main(["check", str(d)]) == 4
    out = capsys.readouterr()
    assert "internal error" not in out.err and "FAIL files" in out.out and "report.json: JSON nested" in out.out
    (d / "flat.json").write_text(DEEP)
    assert main(["check", str(d)]) == 4
    out = capsys.readouterr()
    assert "internal error" not in out.err and "Traceback" not in out.err
    assert "FAIL flat" in out.out and "flat.json: not a readable flat data file (JSON nested deeper" in out.out
