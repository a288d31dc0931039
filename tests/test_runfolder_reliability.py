"""A run deletes only what it made (issue #32): the lock-file sweep of ``run`` / ``offset`` / ``batch``
and of the supervisor leaves a user's ``.*.lock`` files and files another program holds with ``lockf``;
an old run folder that cannot be deleted is named, not left as a hidden ``.part``.  Real files in
tmp_path, real processes where holding a lock is what matters."""
from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from fabricate.app.pipeline import run_pipeline
from fabricate.app.runfolder import MARKER, clean_stale_parts, publish_run, remove_dead_parts, run_lock
from optimize.atomic import part_dir
from optimize.errors import ConfigError

from _pipeline_fixtures import REPO, tiny_config

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="flock / lockf / chattr: Linux")
ENV = dict(os.environ, PYTHONPATH=str(REPO))

DIES_HOLDING = """
import os, sys
from pathlib import Path
from fabricate.app.runfolder import run_lock
with run_lock(Path(sys.argv[1])):
    os._exit(9)   # killed while it held the lock: its lock file stays
"""

LOCKF_HOLDER = """
import fcntl, os, sys, time
fd = os.open(sys.argv[1], os.O_RDWR)
fcntl.lockf(fd, fcntl.LOCK_EX)
print("HELD", flush=True)
time.sleep(120)
"""


def stale_lock(out, name="tiny"):
    """The lock file a run of ``name`` left when it was killed (a real one, written by run_lock)."""
    subprocess.run([sys.executable, "-c", DIES_HOLDING, str(out / name)], env=ENV, check=False)
    path = out / f".{name}.lock"
    assert path.is_file()
    return path


@contextlib.contextmanager
def held_with_lockf(path):
    """Another program holding ``path`` with a POSIX record lock (lockf), as long as the block runs."""
    proc = subprocess.Popen([sys.executable, "-c", LOCKF_HOLDER, str(path)], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "HELD"
        yield
    finally:
        proc.kill()
        proc.wait()


SWEEPS = {"run": lambda out: run_pipeline(tiny_config(out.parent), out, force=True),
          "offset / batch": lambda out: clean_stale_parts(out, "tiny"),
          "supervisor": lambda out: remove_dead_parts(out)}


@pytest.mark.parametrize("sweep", list(SWEEPS))
def test_a_users_lock_files_survive_the_sweep(tmp_path, sweep):
    out = tmp_path / "out"
    out.mkdir()
    notes = out / ".notes.lock"
    notes.write_text("my notes: call the glazier on Monday\n")
    empty = out / ".editor.lock"
    empty.touch()
    theirs = out / ".db.lock"
    theirs.write_text("4242\n")
    with held_with_lockf(theirs):
        SWEEPS[sweep](out)
    assert notes.read_text() == "my notes: call the glazier on Monday\n"
    assert empty.is_file() and theirs.read_text() == "4242\n"


@pytest.mark.parametrize("sweep", list(SWEEPS))
def test_a_stale_lock_of_ours_goes_unless_another_program_holds_it(tmp_path, sweep):
    out = tmp_path / "out"
    out.mkdir()
    lock = stale_lock(out, "other")
    before = lock.read_bytes()
    with held_with_lockf(lock):
        SWEEPS[sweep](out)
        assert lock.read_bytes() == before     # held with lockf by another process: not ours to take
    SWEEPS[sweep](out)
    assert not lock.exists()                   # free, ours, its run dead: removed


def test_a_users_file_in_the_way_of_the_lock_is_not_overwritten(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    mine = out / ".tiny.lock"
    mine.write_text("my notes\n")
    with pytest.raises(ConfigError, match=r"\.tiny\.lock: .*not written by conical-fab.*nothing was written"):
        run_pipeline(tiny_config(tmp_path), out)
    assert mine.read_text() == "my notes\n" and sorted(p.name for p in out.iterdir()) == [".tiny.lock"]


def test_a_stale_lock_of_ours_is_taken_over_and_removed(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    stale_lock(out)
    with run_lock(out / "tiny"):
        pass
    assert list(out.iterdir()) == []


# -- an old run folder that cannot be deleted ------------------------------------------------------
@contextlib.contextmanager
def undeletable(path):
    """``path`` (a file) cannot be deleted while the block runs: immutable for root (chmod does not
    stop root), its folder read-only for anyone else."""
    if os.geteuid() == 0:
        proc = subprocess.run(["chattr", "+i", str(path)], capture_output=True, text=True)
        if proc.returncode:
            pytest.skip(f"chattr +i not possible here: {proc.stderr.strip()}")
        undo = ["chattr", "-i", str(path)]
    else:
        os.chmod(path.parent, 0o555)
        undo = None
    try:
        yield
    finally:
        for p in path.parent.parent.rglob(path.name):
            if undo:
                subprocess.run(["chattr", "-i", str(p)], check=False)
            else:
                os.chmod(p.parent, 0o755)


def test_an_old_run_that_cannot_be_deleted_is_named_and_the_new_one_is_complete(tmp_path):
    out = tmp_path / "out"
    first = run_pipeline(tiny_config(tmp_path), out)
    assert first.exit_code == 0
    with undeletable(out / "tiny" / "report.json"):
        summary = run_pipeline(tiny_config(tmp_path), out, force=True)
        assert summary.exit_code == 0 and summary.status == "ok"      # the new result is complete
        left = [p for p in out.iterdir() if p.name != "tiny"]
        assert len(left) == 1 and not left[0].name.startswith("."), left   # no hidden .part
        note = [n for n in summary.notes if "could not be deleted" in n]
        assert len(note) == 1 and "\n" not in note[0], summary.notes
        assert str(out / "tiny") in note[0] and f"{left[0]}: delete it" in note[0]
        assert f": {left[0] / 'report.json'})" in note[0]            # why: the file that stayed
        assert note[0] in summary.message
        assert (left[0] / "report.json").is_file() and (out / "tiny" / MARKER).is_file()


def test_publish_run_says_where_an_undeletable_old_folder_went(tmp_path):
    target = tmp_path / "job"
    target.mkdir()
    (target / "a.txt").write_text("old")
    tmp = part_dir(target)
    (tmp / "a.txt").write_text("new")
    with undeletable(target / "a.txt"):
        dest, note = publish_run(tmp, target, None, 0)
        assert dest == target and (target / "a.txt").read_text() == "new"
        moved = [p for p in tmp_path.iterdir() if p != target]
        assert [p.name[:len("job.old-")] for p in moved] == ["job.old-"]
        assert (moved[0] / "a.txt").read_text() == "old"
        assert note.startswith(f"the earlier run in {target} was replaced but could not be deleted") and str(moved[0]) in note


DIES_WITH_A_PART = """
import os, sys
from pathlib import Path
from optimize.atomic import part_dir
p = part_dir(Path(sys.argv[1]))
(p / "model.step").write_bytes(b"x" * 100000)
print(p, flush=True)
os._exit(9)
"""


def test_a_dead_runs_folder_that_cannot_be_removed_is_not_said_removed(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    dead = Path(subprocess.run([sys.executable, "-c", DIES_WITH_A_PART, str(out / "tiny")], capture_output=True,
                               text=True, env=ENV).stdout.strip())
    with undeletable(dead / "model.step"):
        notes = clean_stale_parts(out, "tiny")
        assert len(notes) == 1 and notes[0].startswith(f"could not remove {dead} (0.1 MB left: "), notes
        assert remove_dead_parts(out) == [] and dead.is_dir()
    assert clean_stale_parts(out, "tiny")[0].startswith(f"removed {dead} (0.1 MB)")  # its owner record stayed
    assert not dead.exists()
