"""The full check in two lanes: the STEP read and the checks that need it in a child process,
the others in this one, at the same time.

The text reader's STEP check is the longest single check of a big run (a 165 MB file: about
4 s of CPU); nothing else waits for it but the flat data check (which compares each part with
its STEP solid) and the DXF check (which looks up every outline's solid by name).  So
:data:`CHILD_CHECKS` run in ``python -m fabricate.check_lanes`` while this process runs the
3MF, STL, intersection, bearing, SVG and exchange-file checks; the child's results are merged
in the usual order.  The results are the same as one lane's (a test holds it so): the child
runs :func:`fabricate.check._check_outputs` itself, on the same files, with the same readers.

Only where it pays: a STEP file of at least :data:`LANE_BYTES` (the child's start, about
0.5 s of imports, is hidden behind this lane's work), on Linux, with two CPUs free to this
process.  When the child cannot be started or fails (no such interpreter, killed, a result
that does not unpickle) its checks run here after all, so a check is never lost.
"""
from __future__ import annotations

import logging
import os
import pickle
import signal
import subprocess
import sys
from pathlib import Path

log = logging.getLogger(__name__)
CHILD_CHECKS = frozenset({"step", "flat", "dxf"})
LANE_BYTES = 16 << 20


def worth_a_child(step_path: Path, step_reader: str) -> bool:
    """Whether the STEP check of ``step_path`` goes to a child process (see the module's text)."""
    if step_reader != "text" or not sys.platform.startswith("linux") or len(os.sched_getaffinity(0)) < 2:
        return False
    try:
        return step_path.stat().st_size >= LANE_BYTES
    except OSError:
        return False


def start(outdir: Path, skip: frozenset[str]) -> subprocess.Popen | None:
    """The child running :data:`CHILD_CHECKS` on ``outdir``; None when it cannot be started."""
    import fabricate

    root = str(Path(fabricate.__file__).resolve().parents[1])   # the child imports this very package
    code = (f"import sys; sys.path.insert(0, {root!r}); "
            "from fabricate.check_lanes import main; main()")
    try:
        return subprocess.Popen([sys.executable, "-c", code, str(outdir), ",".join(sorted(skip))],
                                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    except OSError as exc:
        log.warning("check: the STEP read runs in this process (no child: %s)", exc)
        return None


def collect(proc: subprocess.Popen) -> dict | None:
    """The child's ``{name: result}``; None when it failed (its last line of stderr is logged)."""
    try:
        out, err = proc.communicate()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    last = (err.decode("utf-8", "replace").strip().splitlines() or ["no message"])[-1]
    if proc.returncode == 0:
        try:
            checks = pickle.loads(out)
        except Exception as exc:  # noqa: BLE001 - any undecodable answer means: run the checks here
            checks, last = None, f"its answer does not read: {exc}"
        if isinstance(checks, dict):
            return checks
    log.warning("check: the child process failed (exit %s: %s); its checks run here", proc.returncode, last[:200])
    return None


def stop(proc: subprocess.Popen | None) -> None:
    """End the child when this lane failed or was interrupted."""
    if proc is not None and proc.poll() is None:
        proc.kill()
        proc.wait()


def main() -> None:
    """The child: ``OUTDIR SKIP`` (comma list) -> pickled ``{name: result}`` of CHILD_CHECKS on stdout."""
    signal.signal(signal.SIGINT, lambda *_: os._exit(130))       # Ctrl-C reaches the parent, which cleans up
    from .check import _check_outputs, heap_reuse

    outdir, skip = Path(sys.argv[1]), frozenset(s for s in sys.argv[2].split(",") if s)
    with heap_reuse():
        checks = _check_outputs(outdir, skip=skip, only=CHILD_CHECKS)["checks"]
    sys.stdout.buffer.write(pickle.dumps({k: v for k, v in checks.items() if k in CHILD_CHECKS}))
