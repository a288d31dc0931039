"""The full check's lanes (the STEP read, the IFC check in child processes) give the same results as one
lane, fall back to one lane when the child fails, and leave no child behind; the STEP reader's
reals near the end of a file; numpy's huge-page advice restored after the check."""
import contextlib
import os
import shutil
import sys

import numpy as np
import pytest
from cad_fixtures import dome_parts

import fabricate.check_lanes as lanes
import fabricate.export as ex
from fabricate.check import check_outputs
from fabricate.check_heap import heap_reuse
from fabricate.export.step_tokens import Records
from optimize.errors import ExportError

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="two lanes only on Linux")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    parts = dome_parts(5, 3)
    folder = tmp_path_factory.mktemp("lanes")
    for name, fn in (("model.step", ex.write_step), ("model.stl", ex.write_stl), ("model.3mf", ex.write_3mf),
                     ("outlines.dxf", ex.write_dxf), ("outlines.svg", ex.write_svg), ("flat.json", ex.write_flat),
                     ("model.ifc", ex.write_ifc), ("bom.csv", ex.write_bom)):
        fn(parts, folder / name)
    return folder


def _without_seconds(result: dict) -> dict:
    return {k: {kk: vv for kk, vv in v.items() if kk != "seconds"} for k, v in result["checks"].items()}


def _checked(folder, monkeypatch, two: bool) -> dict:
    monkeypatch.setattr(lanes, "LANE_BYTES", dict.fromkeys(lanes.LANE_BYTES, 0 if two else 1 << 62))
    started = []
    real_start = lanes.start
    monkeypatch.setattr(lanes, "start", lambda *a: started.append(1) or real_start(*a))
    result = check_outputs(folder)
    assert len(started) == (len(lanes.LANES) if two and len(os.sched_getaffinity(0)) >= 2 else 0)
    return result


def test_two_lanes_give_the_results_of_one(run_dir, monkeypatch):
    one, two = _checked(run_dir, monkeypatch, False), _checked(run_dir, monkeypatch, True)
    assert one["pass"] and two["pass"]
    assert list(two["checks"]) == list(one["checks"])              # the usual order
    assert _without_seconds(two) == _without_seconds(one)
    assert two["checks"]["flat"]["against"] == "step" and two["checks"]["dxf"]["pass"] and two["checks"]["ifc"]["pass"]


def test_a_broken_step_file_reads_the_same_in_the_child(run_dir, tmp_path, monkeypatch):
    bad = tmp_path / "bad"
    shutil.copytree(run_dir, bad)
    text = (bad / "model.step").read_bytes()
    (bad / "model.step").write_bytes(text[:len(text) // 2])         # cut off in the DATA section
    one, two = _checked(bad, monkeypatch, False), _checked(bad, monkeypatch, True)
    assert one["checks"]["step"]["pass"] is False and "error" in one["checks"]["step"]
    assert _without_seconds(two) == _without_seconds(one)
    assert two["checks"]["flat"]["against"] == "3mf"                # no solids: the flat data against the 3MF
    assert two["checks"]["dxf"]["pass"] is True                     # the DXF does not wait for the STEP


@pytest.mark.parametrize("how", ["no interpreter", "fails", "garbage"])
def test_a_failed_child_means_the_checks_run_here(run_dir, monkeypatch, how, caplog):
    one = _without_seconds(_checked(run_dir, monkeypatch, False))
    if how == "no interpreter":
        monkeypatch.setattr(sys, "executable", "/nonexistent/python")
    else:                                    # exits 1 / answers with its arguments, not a pickle
        monkeypatch.setattr(sys, "executable", "/bin/false" if how == "fails" else "/bin/echo")
    monkeypatch.setattr(lanes, "LANE_BYTES", dict.fromkeys(lanes.LANE_BYTES, 0))
    result = check_outputs(run_dir)
    assert _without_seconds(result) == one
    assert "run in this process" in caplog.text or "its checks run here" in caplog.text


def test_an_interrupted_check_leaves_no_child(run_dir, monkeypatch):
    children = []
    real_start = lanes.start
    monkeypatch.setattr(lanes, "LANE_BYTES", dict.fromkeys(lanes.LANE_BYTES, 0))
    monkeypatch.setattr(lanes, "start", lambda *a: children.append(real_start(*a)) or children[-1])

    def interrupted(*a, **k):
        raise KeyboardInterrupt
    monkeypatch.setattr("fabricate.check._check_3mf", interrupted)
    with pytest.raises(KeyboardInterrupt):
        check_outputs(run_dir)
    assert children and all(c is None or c.poll() is not None for c in children)


def test_reals_of_a_short_record_at_the_end_of_the_data():
    """The last point is shorter than the longest: its window would run past the buffer's end."""
    long = ",".join(["-123456789.123456789012"] * 3)
    body = (f"#1=CARTESIAN_POINT('',({long}));\n#2=CARTESIAN_POINT('',(1.,2.,3.));").encode()
    rec = Records(body, 0, len(body), "x.step")
    rows = rec.of(b"CARTESIAN_POINT")
    close = rec.after_string(rows, "point")
    _, _, X = rec.template(rows, close, ",(N))", "point", per=3)
    np.testing.assert_array_equal(X, [[-123456789.123456789012] * 3, [1.0, 2.0, 3.0]])
    bad = body.replace(b"(1.,2.,3.)", b"(1.,2.,x)")
    rec = Records(bad, 0, len(bad), "x.step")
    with pytest.raises(ExportError, match="#2 .*not part of a number"):
        rec.template(rows, rec.after_string(rows, "point"), ",(N))", "point", per=3)


def test_heap_reuse_restores_numpys_huge_page_advice():
    from numpy._core.multiarray import _set_madvise_hugepage

    before = _set_madvise_hugepage(True)
    try:
        with pytest.raises(RuntimeError), heap_reuse():
            assert _set_madvise_hugepage(False) is False               # off inside
            raise RuntimeError
        assert _set_madvise_hugepage(True) is True                     # back on afterwards
    finally:
        _set_madvise_hugepage(before)


KILLED_CHECK = """
import sys, time
import fabricate.check_lanes as lanes

class Slow:
    \"\"\"Unpickled by each child as it starts: it then works on for two minutes, like a big model's check.\"\"\"
    def __reduce__(self):
        return time.sleep, (120,)

real_start = lanes.start
lanes.lanes_for = lambda paths, skip, reader: [names for names, _ in lanes.LANES]
lanes.start = lambda outdir, names, skip, tol: real_start(outdir, names, skip, Slow())
from fabricate.app.cli import main
sys.argv = ["fabricate", "check", sys.argv[1]]
sys.exit(main())
"""


def _children(pid: int) -> list[int]:
    try:
        return [int(c) for t in os.listdir(f"/proc/{pid}/task")
                for c in open(f"/proc/{pid}/task/{t}/children").read().split()]
    except OSError:
        return []


def _running(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[-1].split()[0] not in ("Z", "X")
    except OSError:
        return False


def test_kill_9_of_check_ends_its_child_processes(run_dir):
    """``kill -9`` of ``fabricate check`` (its supervisor) takes the working process and both lanes'
    children with it: none goes on checking unwatched."""
    import signal
    import subprocess
    import time

    from _pipeline_fixtures import REPO

    proc = subprocess.Popen([sys.executable, "-c", KILLED_CHECK, str(run_dir)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, env=dict(os.environ, PYTHONPATH=str(REPO)))
    family: list[int] = []
    try:
        deadline = time.monotonic() + 120          # a hang guard, not a timing: they start, at any load
        while len(family) < 3:                     # the working process and its two lanes
            assert proc.poll() is None and time.monotonic() < deadline, "the check's lanes never started"
            family = [c for w in _children(proc.pid) for c in [w, *_children(w)]]
            time.sleep(0.02)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        deadline = time.monotonic() + 60           # they end at once; the sleep is 120 s
        while any(_running(p) for p in family) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert [p for p in family if _running(p)] == []
    finally:
        for p in family:
            with contextlib.suppress(OSError):
                os.kill(p, signal.SIGKILL)
        if proc.poll() is None:
            proc.kill()
            proc.wait()
