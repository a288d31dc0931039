"""Fuzz of ``fabricate check`` (full and ``--fast``) over mutated copies of one small run folder: a file the
run wrote deleted, cut short, bytes flipped, replaced by a named pipe or a folder, a number in it changed,
bytes appended (the marker too).  Every outcome is exit 0 or 4 with no traceback and no internal error, and
ends (a guard ends a check that hangs); a file the run lists that is gone, not a regular file or of another
size fails (exit 4).

``FUZZ_EXAMPLES`` (default 30 here) sets the number of cases; the search is derandomized."""
from __future__ import annotations

import os
import re
import shutil
import signal
from pathlib import Path

import pytest
from _fuzz_common import FUZZ
from hypothesis import given, settings
from hypothesis import strategies as st
from test_check_runfolder import build_run

from fabricate.app.cli import main
from fabricate.app.runfolder import MARKER

EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "30"))
GUARD_S = 120
"""Seconds one check may take before the guard ends it as hung (a check takes well under a second)."""
OPS = ("delete", "truncate", "flip", "fifo", "folder", "number", "append")
NUMBER = re.compile(rb"-?[0-9]+(?:\.[0-9]+)?(?:[eE][+-]?[0-9]+)?")
NEW_NUMBERS = (b"0", b"-1", b"1e309", b"nan", b"abc", b"", b"99999999", b"0.5", b"-0", b"1.0000001")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    return build_run(tmp_path_factory.mktemp("fuzzrun"))


def _targets(run_dir: Path) -> list[str]:
    """The files to mutate: every file the run lists (two of its NC1 files), and the marker."""
    import json

    listed = sorted(json.loads((run_dir / MARKER).read_text())["files"])
    nc1 = [n for n in listed if n.startswith("nc1/")]
    return [n for n in listed if not n.startswith("nc1/")] + nc1[:2] + [MARKER]


class Mutation(tuple):
    """(file, operation, mode, argument) with a short repr (hypothesis prints failing cases)."""

    def __repr__(self):
        name, op, mode, arg = self
        return f"Mutation({name!r}, {op}, {mode}, {arg!r:.200})"


@st.composite
def mutations(draw, names: list[str]):
    name = draw(st.sampled_from(names))
    op = draw(st.sampled_from(OPS))
    arg = {"truncate": st.floats(0.0, 0.999),
           "flip": st.lists(st.tuples(st.floats(0.0, 0.999), st.integers(1, 255)), min_size=1, max_size=4),
           "number": st.tuples(st.floats(0.0, 0.999), st.sampled_from(NEW_NUMBERS)),
           "append": st.binary(min_size=1, max_size=64)}.get(op, st.none())
    return Mutation((name, op, "full" if draw(st.booleans()) else "fast", draw(arg)))


def _mutate(path: Path, op: str, arg) -> None:
    if op in ("delete", "fifo", "folder"):
        path.unlink()
        if op == "fifo":
            os.mkfifo(path)
        elif op == "folder":
            path.mkdir()
        return
    data = bytearray(path.read_bytes())
    if op == "truncate":
        data = data[:int(len(data) * arg)]
    elif op == "flip":
        for at, mask in arg:
            if data:
                data[int(len(data) * at)] ^= mask
    elif op == "number":
        found = list(NUMBER.finditer(data))
        if found:
            m = found[int(len(found) * arg[0])]
            data[m.start():m.end()] = arg[1]
    elif op == "append":
        data += arg
    path.write_bytes(bytes(data))


def _hung(signum, frame):
    raise TimeoutError(f"fabricate check took more than {GUARD_S} s: hung")


def test_check_of_a_mutated_run_folder_fails_cleanly(run_dir, tmp_path, capsys):
    names = _targets(run_dir)
    count = [0]

    @settings(FUZZ, max_examples=EXAMPLES)
    @given(case=mutations(names))
    def one(case):
        name, op, mode, arg = case
        count[0] += 1
        d = tmp_path / f"case{count[0]}"
        shutil.copytree(run_dir, d)
        path = d / name
        size = path.stat().st_size
        _mutate(path, op, arg)
        changed = not path.is_file() or path.stat().st_size != size      # stat only: a pipe is not opened
        capsys.readouterr()
        old = signal.signal(signal.SIGALRM, _hung)
        signal.alarm(GUARD_S)
        try:
            rc = main(["check", str(d)] + (["--fast"] if mode == "fast" else []))
        finally:
            signal.alarm(0)
            signal.signal(signal.SIGALRM, old)
        out = capsys.readouterr()
        shutil.rmtree(d, ignore_errors=True)
        assert rc in (0, 4), (rc, out.err[-2000:])
        assert "Traceback" not in out.err and "internal error" not in out.err, out.err[-2000:]
        if name != MARKER and changed:   # the files row fails, or the check ends at once (no bill of materials)
            assert rc == 4 and ("FAIL files" in out.out and name in out.out or name in out.err), out

    one()

