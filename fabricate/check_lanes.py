"""The full check in lanes: the STEP read and the checks that need it in one child process, the
IFC check in another, the others in this one, at the same time.

The text reader's STEP check is the longest single check of a big run (a 165 MB file: about
4 s of CPU); nothing else waits for it but the flat data check (which compares each part with
its STEP solid).  The IFC
check's schema validation (ifcopenshell's, in Python: about 10 s for the railway station's
12,000 elements) needs nothing else.  So each group of :data:`LANES` whose file is big enough
runs in a child (``python -c 'from fabricate.check_lanes import main; main()'``) while this
process runs the 3MF, STL, intersection, bearing, DXF, SVG, 3dm and NC1 checks; the children's
results are merged in the usual order.  The results are the same as one lane's (a test holds
it so): a child runs :func:`fabricate.check._check_outputs` itself, on the same files, with the
same readers.

Only where it pays: a file of at least its lane's bytes (a child's start, about 0.5 s of
imports, is hidden behind this lane's work), the text reader, on Linux, with two CPUs free to
this process.  When a child cannot be started or fails (no such interpreter, killed, a result
that does not unpickle) its checks run here after all, so a check is never lost.

A child dies with this process (Linux ``PR_SET_PDEATHSIG``, the rule of the supervisor's working
process): ``kill -9`` of ``fabricate check`` leaves no lane checking on unwatched.
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
LANES = ((frozenset({"step", "flat"}), "step"), (frozenset({"ifc"}), "ifc"))
"""Checks run together in a child, and the key (of ``fabricate.check.FILES``) of the file whose size decides."""
LANE_BYTES = {"step": 16 << 20, "ifc": 4 << 20}


def lanes_for(paths: dict[str, Path], skip: frozenset[str], step_reader: str) -> list[frozenset[str]]:
    """The groups of :data:`LANES` that go to child processes here (see the module's text)."""
    if step_reader != "text" or not sys.platform.startswith("linux") or len(os.sched_getaffinity(0)) < 2:
        return []
    out = []
    for names, key in LANES:
        try:
            if key not in skip and paths[key].stat().st_size >= LANE_BYTES[key]:
                out.append(names)
        except OSError:
            continue
    return out


def start(outdir: Path, names: frozenset[str], skip: frozenset[str], tol) -> subprocess.Popen | None:
    """The child running the checks ``names`` on ``outdir`` with the tolerances ``tol`` (pickled to
    its stdin); None when it cannot be started."""
    import fabricate

    root = str(Path(fabricate.__file__).resolve().parents[1])   # the child imports this very package
    code = (f"import sys; sys.path.insert(0, {root!r}); "
            "from fabricate.check_lanes import main; main()")
    try:
        proc = subprocess.Popen([sys.executable, "-c", code, str(outdir), ",".join(sorted(names)),
                                 ",".join(sorted(skip)), str(os.getpid())],
                                stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    except OSError as exc:
        log.warning("check: %s run in this process (no child: %s)", ", ".join(sorted(names)), exc)
        return None
    stdin, proc.stdin = proc.stdin, None      # communicate() later reads only
    try:
        with stdin:
            stdin.write(pickle.dumps(tol))
    except OSError:                # it ended already: collect() says why
        pass
    return proc


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
    """The child: ``OUTDIR NAMES SKIP PARENT`` (comma lists, the parent's pid) -> pickled ``{name: result}``
    of NAMES on stdout."""
    signal.signal(signal.SIGINT, lambda *_: os._exit(130))       # Ctrl-C reaches the parent, which cleans up
    from .app.cli.supervise import _die_with

    _die_with(int(sys.argv[4]))                                  # killed with the parent, even by kill -9
    from .check import _check_outputs
    from .check_heap import heap_reuse

    outdir = Path(sys.argv[1])
    names, skip = (frozenset(s for s in arg.split(",") if s) for arg in sys.argv[2:4])
    tol = pickle.loads(sys.stdin.buffer.read())
    with heap_reuse():
        checks = _check_outputs(outdir, tol, skip=skip, only=names)["checks"]
    sys.stdout.buffer.write(pickle.dumps({k: v for k, v in checks.items() if k in names}))
