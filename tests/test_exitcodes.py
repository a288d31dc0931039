"""Every failure maps to its exit code and one line (issue #15 section 3): one table
(fabricate.app.cli.exits.classify) for every command, checked on the exceptions users met and
through the real command line."""
from __future__ import annotations

import errno
import os
import subprocess
import sys

import pytest

from fabricate.app.batch import exit_code, expand_jobs
from fabricate.app.cli import main
from fabricate.app.cli.exits import classify
from fabricate.app.pipeline import RunSummary
from optimize.errors import ConfigError, ConvergenceError, ExportError, MeshError

from _pipeline_fixtures import REPO

ENV = dict(os.environ, PYTHONPATH=str(REPO))


def cli(*args, cwd=None, **kw):
    return subprocess.run([sys.executable, "-m", "fabricate", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=300, env=ENV, **kw)


@pytest.mark.parametrize("exc,code,fragment", [
    (ConfigError("job.yaml:3: optimize.targte: unknown key"), 2, "job.yaml:3"),
    (MeshError("grid.obj:7: face index 9"), 2, "grid.obj:7"),
    (ConvergenceError("stalled"), 3, "stalled"),
    (ExportError("model.step: export failed"), 4, "model.step"),
    (FileNotFoundError(errno.ENOENT, "No such file or directory", "/no/such/dir/x.obj"), 2, "/no/such/dir/x.obj"),
    (FileExistsError(errno.EEXIST, "File exists", "out/afile"), 2, "out/afile: File exists"),
    (NotADirectoryError(errno.ENOTDIR, "Not a directory", "out/afile/run"), 2, "Not a directory"),
    (PermissionError(errno.EACCES, "Permission denied", "/root/x"), 2, "/root/x: Permission denied"),
    (OSError(errno.ENAMETOOLONG, "File name too long", "out/" + "n" * 300), 2, "File name too long"),
    (OSError(errno.ENOSPC, "No space left on device", "out/model.step"), 4, "could not be written"),
    (UnicodeDecodeError("utf-8", b"\xe9", 0, 1, "invalid continuation byte"), 2, "not UTF-8"),
    (KeyboardInterrupt(), 130, "interrupted"),
])
def test_each_kind_of_failure_has_its_code_and_one_line(exc, code, fragment):
    got, line = classify(exc)
    assert got == code and fragment in line and "\n" not in line


def test_a_bug_is_an_internal_error_with_its_traceback_in_a_log(monkeypatch, capsys, tmp_path):
    import fabricate.app.cli.cmd_shapes as cmd_shapes

    def bug(args):
        raise TypeError("unsupported operand type(s) for +: 'int' and 'str'")

    monkeypatch.setattr(cmd_shapes, "run", bug)
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", None)
    assert main(["shapes"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("error: internal error, please report: TypeError: unsupported operand")
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    log = err.split("traceback in ")[1].split(";")[0].split(")")[0]
    text = open(log).read()
    assert log.startswith(str(tmp_path)) and "Traceback" in text and "in bug" in text


def test_broken_pipe_is_silent(tmp_path):
    from optimize.modelling import shapes
    from optimize.mesh.io import write_mesh

    write_mesh(tmp_path / "big.obj", shapes.grid(60, 60))
    proc = subprocess.Popen([sys.executable, "-m", "fabricate", "measure", str(tmp_path / "big.obj")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=ENV)
    proc.stdout.close()  # what `| head` does once it has its lines: here before a byte was written
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 141, err
    assert err == "", err  # no traceback, no "Exception ignored ... BrokenPipeError"


def test_paths_that_cannot_be_used_are_bad_input(tmp_path, capsys):
    (tmp_path / "afile").write_text("x")
    cfg = tmp_path / "c.yaml"
    cfg.write_text("input:\n  shape: {name: dome}\n")
    cases = [(["run", str(cfg), "--out", str(tmp_path / "afile"), "-q"], "a file is in the way"),
             (["run", str(cfg), "--out", str(tmp_path / "afile" / "deeper"), "-q"], "cannot create the folder"),
             (["run", str(cfg), "--out", str(tmp_path / ("n" * 300)), "-q"], "(File name too long)"),
             (["check", "/nonexistent"], "/nonexistent: does not exist; expected the output folder of a run"),
             (["check", str(tmp_path)], "is not the output folder of a run"),
             (["measure", str(tmp_path / "missing.obj")], "missing.obj")]
    for argv, fragment in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert fragment in err and len(err.strip().splitlines()) == 1, (argv, err)
    proc = cli("check", "/nonexistent")  # the same through the real entry point (supervised)
    assert proc.returncode == 2 and proc.stderr.startswith("error: /nonexistent: does not exist"), proc.stderr


def test_a_job_name_too_long_for_a_folder_is_a_bad_job(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("name: " + "x" * 120 + "\ninput:\n  shape: {name: dome}\n")
    from fabricate.app.batch import parse_sets

    jobs = expand_jobs([cfg], parse_sets(["parts.glass_thickness=8,10", "parts.beam_width=60,80",
                                          "parts.beam_depth=150,200", "parts.joint_gap=10,12",
                                          "parts.node_radius=100,120", "parts.density_glass=2500.5,2600.5"]))
    assert jobs and all(j.config is None and "expected at most 200" in j.error for j in jobs)


def test_batch_exit_code_puts_a_lost_or_crashed_job_first():
    def s(status, code):
        return RunSummary(status, status, code)

    assert exit_code([s("ok", 0), s("tolerance_not_reached", 3), s("bad_input", 2), s("lost", 1)]) == 1
    assert exit_code([s("export_failed", 4), s("error", 1)]) == 1
    assert exit_code([s("export_failed", 4), s("bad_input", 2)]) == 2
    assert exit_code([s("tolerance_not_reached", 3), s("export_failed", 4)]) == 4
    assert exit_code([s("ok", 0), s("tolerance_not_reached", 3)]) == 3
    assert exit_code([s("ok", 0)]) == 0 and exit_code([]) == 0
