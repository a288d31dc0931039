"""``fabricate check`` of a run folder holds it to the list of files the run wrote (its marker, else
``report.json``): a listed file that is gone, not a regular file or not of the size the run wrote fails,
also without ``report.json``; a file that is not a regular file (a named pipe) is never opened; every
failed row names what failed (no ``None``)."""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from _pipeline_fixtures import NO_FILES, REPO, tiny_config

from fabricate.app.cli import main
from fabricate.app.pipeline import run_pipeline
from fabricate.app.runfolder import MARKER
from fabricate.check_fast import run_check

HANG_GUARD_S = 120
"""A check that opens a named pipe blocks for ever: the subprocess is ended after this."""


def build_run(root: Path) -> Path:
    """A finished run of the 12-quad dome with every file the check reads (a second or so)."""
    outputs = {k: True for k in NO_FILES} | {"pictures": False, "html": False, "gltf": False}
    summary = run_pipeline(tiny_config(root, outputs=outputs), root / "out")
    assert summary.status == "ok", summary
    return Path(summary.out_dir)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    return build_run(tmp_path_factory.mktemp("checkrun"))


def _copy(run_dir, tmp_path, name="out") -> Path:
    d = tmp_path / name
    shutil.copytree(run_dir, d)
    return d


def _rows_of(out: str) -> dict[str, str]:
    """``{check: its line}`` of the text ``fabricate check`` prints."""
    return {x.split()[1]: x for x in out.splitlines() if x[:5] in ("ok   ", "FAIL ", "skip ")}


def _rows(capsys) -> dict[str, str]:
    return _rows_of(capsys.readouterr().out)


def test_the_run_as_written_passes_with_its_files_row(run_dir, capsys):
    assert main(["check", str(run_dir)]) == 0
    rows = _rows(capsys)
    assert rows["files"].startswith("ok") and rows["step"].startswith("ok") and rows["ifc"].startswith("ok")
    c = run_check(run_dir, "full")["checks"]["files"]
    listed = json.loads((run_dir / MARKER).read_text())["files"]
    assert c["pass"] is True and c["listed"] == len(listed) and c["listed_by"] == f"{MARKER} and report.json"


@pytest.mark.parametrize("fast", [False, True])
def test_step_and_ifc_deleted_without_report_json_fail(run_dir, tmp_path, capsys, fast):
    """The marker lists them: gone, they fail (they were 'not written' and the check passed)."""
    d = _copy(run_dir, tmp_path)
    for name in ("report.json", "model.step", "model.ifc"):
        (d / name).unlink()
    assert main(["check", str(d)] + (["--fast"] if fast else [])) == 4
    rows = _rows(capsys)
    assert rows["step"].startswith("FAIL") and "model.step is missing" in rows["step"], rows["step"]
    assert rows["ifc"].startswith("FAIL") and "model.ifc is missing" in rows["ifc"], rows["ifc"]
    assert rows["files"].startswith("FAIL") and "report.json" in rows["files"], rows["files"]


def test_report_json_alone_missing_fails(run_dir, tmp_path, capsys):
    d = _copy(run_dir, tmp_path)
    (d / "report.json").unlink()
    assert main(["check", str(d)]) == 4
    rows = _rows(capsys)
    assert rows["files"].startswith("FAIL") and "report.json" in rows["files"]
    assert [k for k, v in rows.items() if v.startswith("FAIL")] == ["files"]


def test_a_listed_file_no_check_reads_gone_or_cut_short_fails(run_dir, tmp_path, capsys):
    d = _copy(run_dir, tmp_path)
    (d / "glass_schedule.csv").unlink()
    text = (d / "config.yaml").read_bytes()
    (d / "config.yaml").write_bytes(text[:-10])
    assert main(["check", str(d)]) == 4
    row = _rows(capsys)["files"]
    assert "glass_schedule.csv" in row and f"config.yaml: {len(text) - 10} bytes, the run wrote {len(text)}" in row


def test_an_unreadable_marker_fails(run_dir, tmp_path, capsys):
    d = _copy(run_dir, tmp_path)
    (d / MARKER).write_bytes((d / MARKER).read_bytes()[:100])
    assert main(["check", str(d)]) == 4
    row = _rows(capsys)["files"]
    assert row.startswith("FAIL") and MARKER in row


def test_without_marker_report_json_lists_the_files(run_dir, tmp_path, capsys):
    d = _copy(run_dir, tmp_path)
    (d / MARKER).unlink()
    assert main(["check", str(d)]) == 0                 # report.json lists the owner record too: not a file
    (d / "model.step").unlink()
    assert main(["check", str(d)]) == 4
    assert "model.step is missing" in _rows(capsys)["step"]


def test_cut_files_gone_are_named_not_none(run_dir, tmp_path, capsys):
    d = _copy(run_dir, tmp_path)
    for p in d.glob("cut_*.dxf"):
        p.unlink()
    assert main(["check", str(d)]) == 4
    row = _rows(capsys)["cut"]
    assert "None" not in row and "cut_glass_10mm.dxf" in row and "cut_steel_60mm.dxf" in row, row


def _check_subprocess(d: Path, *flags: str) -> subprocess.CompletedProcess:
    try:
        return subprocess.run([sys.executable, "-m", "fabricate", "check", str(d), *flags], cwd=REPO,
                              capture_output=True, text=True, timeout=HANG_GUARD_S)
    except subprocess.TimeoutExpired:
        pytest.fail(f"fabricate check {' '.join(flags)} did not end in {HANG_GUARD_S} s: it opened a named pipe")


PIPES = ("model.step", "flat.json", "outlines.dxf", "cut_steel_60mm.dxf", "model.3mf", "nc1/B0001.nc1")


@pytest.mark.parametrize("flags", [(), ("--fast",)])
def test_named_pipes_are_refused_unopened(run_dir, tmp_path, flags):
    d = _copy(run_dir, tmp_path)
    for name in PIPES:
        (d / name).unlink()
        os.mkfifo(d / name)
    proc = _check_subprocess(d, *flags)
    assert proc.returncode == 4, proc.stderr
    assert "Traceback" not in proc.stderr and "internal error" not in proc.stderr
    rows = _rows_of(proc.stdout)
    fails = {k for k, v in rows.items() if v.startswith("FAIL")}
    assert {"files", "flat", "dxf", "cut", "3mf", "nc1", "step"} <= fails, proc.stdout
    for name in ("flat", "dxf", "cut", "3mf", "nc1", "step"):
        assert "a named pipe" in rows[name], rows[name]
    assert ("6 not a file (refused unopened): cut_steel_60mm.dxf (a named pipe), flat.json (a named pipe)"
            in rows["files"])


def test_a_marker_and_report_that_are_named_pipes_fail(run_dir, tmp_path):
    d = _copy(run_dir, tmp_path)
    for name in (MARKER, "report.json"):
        (d / name).unlink()
        os.mkfifo(d / name)
    proc = _check_subprocess(d)
    assert proc.returncode == 4, proc.stderr
    row = _rows_of(proc.stdout)["files"]
    assert f"{MARKER}: a named pipe" in row and "report.json: a named pipe" in row, row


def test_a_bom_that_is_a_named_pipe_fails_in_one_line(run_dir, tmp_path):
    d = _copy(run_dir, tmp_path)
    (d / "bom.csv").unlink()
    os.mkfifo(d / "bom.csv")
    proc = _check_subprocess(d)
    assert proc.returncode == 4 and "bom.csv" in proc.stderr and "a named pipe" in proc.stderr, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1


def test_a_folder_where_a_file_was_fails(run_dir, tmp_path, capsys):
    d = _copy(run_dir, tmp_path)
    (d / "model.stl").unlink()
    (d / "model.stl").mkdir()
    assert main(["check", str(d)]) == 4
    rows = _rows(capsys)
    assert "model.stl" in rows["stl"] and "a folder" in rows["stl"] and "model.stl" in rows["files"]


def test_the_nc1_folder_gone_fails_with_its_count(run_dir, tmp_path, capsys):
    d = _copy(run_dir, tmp_path)
    shutil.rmtree(d / "nc1")
    assert main(["check", str(d)]) == 4
    rows = _rows(capsys)
    assert "nc1 is missing: the run wrote it (30 files)" in rows["nc1"], rows["nc1"]
    assert "30 missing (the run wrote them): nc1/B0001.nc1" in rows["files"], rows["files"]
