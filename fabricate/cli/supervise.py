"""Ctrl-C ends a command within two seconds, at any moment, with exit 130 and no traceback.

Python handles a signal only between bytecodes: inside one long call into
OpenCASCADE, MKL or numba it would wait until that call returns (a STEP
read-back of a large model takes a minute).  So the ``fabricate`` command runs
its work in a forked child in a process group of its own and stays a small
supervisor: it forwards SIGINT / SIGTERM / SIGHUP to that group (the child
turns the first into KeyboardInterrupt and unwinds, removing its temporary
folders), and when the group has not ended :data:`GRACE` seconds later it kills
it (batch workers included) and removes the temporary folders the killed
processes left (:func:`fabricate.runfolder.clean_stale_parts`).
Ctrl-Z stops the whole group and ``fg`` resumes it.
"""
from __future__ import annotations

import contextlib
import os
import signal
import sys
import time
from pathlib import Path
from typing import Callable, Iterable

GRACE = 1.5
"""Seconds the work may take to unwind after a signal before it is killed."""
FORWARDED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


def interrupt_handler(signum, frame):
    """In the working process: the first signal unwinds (KeyboardInterrupt); later ones are ignored
    so that they cannot break off the clean-up the first one started."""
    for sig in FORWARDED:
        signal.signal(sig, signal.SIG_IGN)
    raise KeyboardInterrupt(f"signal {signum}")


def supervise(work: Callable[[], int], folders: Callable[[], Iterable[Path]]) -> int:
    """Run ``work()`` (returns an exit code, raises nothing) in a supervised child; its exit code.

    folders : where the work writes temporary folders (cleaned when it had to be killed).
    """
    if not hasattr(os, "fork") or os.environ.get("CONICAL_FAB_NO_SUPERVISOR"):
        for sig in FORWARDED:
            signal.signal(sig, interrupt_handler)
        return work()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    pid = os.fork()
    if pid == 0:  # the child: do the work, never return into the caller
        code = 1
        try:
            os.setpgid(0, 0)
            for sig in FORWARDED:
                signal.signal(sig, interrupt_handler)
            signal.signal(signal.SIGTSTP, signal.SIG_DFL)
            code = work()
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        except BaseException:  # noqa: BLE001 - work() maps its own errors; this is the last guard
            code = 1
        finally:
            for stream in (sys.stdout, sys.stderr):
                with contextlib.suppress(Exception):
                    stream.flush()
            os._exit(code)
    return _watch(pid, folders)


def _watch(pid: int, folders: Callable[[], Iterable[Path]]) -> int:
    with contextlib.suppress(OSError):
        os.setpgid(pid, pid)  # also here: no window in which a signal reaches the old group only
    state = {"signal": None, "deadline": None}

    def forward(signum, frame):
        if state["signal"] is None:
            state["deadline"] = time.monotonic() + GRACE
        state["signal"] = signum
        with contextlib.suppress(OSError):
            os.killpg(pid, signum)

    def stop(signum, frame):  # Ctrl-Z: stop the work too, resume it with ourselves
        with contextlib.suppress(OSError):
            os.killpg(pid, signal.SIGSTOP)
        signal.signal(signal.SIGTSTP, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTSTP)
        signal.signal(signal.SIGTSTP, stop)
        with contextlib.suppress(OSError):
            os.killpg(pid, signal.SIGCONT)

    for sig in FORWARDED:
        signal.signal(sig, forward)
    signal.signal(signal.SIGTSTP, stop)
    killed, status = False, 0
    while True:
        try:
            done, status = os.waitpid(pid, os.WNOHANG)
        except ChildProcessError:
            break
        if done:
            break
        if state["deadline"] is not None and not killed and time.monotonic() > state["deadline"]:
            with contextlib.suppress(OSError):
                os.killpg(pid, signal.SIGKILL)
            killed = True
        time.sleep(0.02)
    with contextlib.suppress(OSError):
        os.killpg(pid, signal.SIGKILL)  # nothing of the group may go on writing after we return
    died = os.WTERMSIG(status) if os.WIFSIGNALED(status) else None
    if killed or died is not None:
        removed = _clean(folders)
    if state["signal"] is not None:
        if killed:
            extra = f"; removed {', '.join(removed)}" if removed else ""
            print(f"interrupted (stopped after {GRACE:g} s{extra})", file=sys.stderr)
        elif died is not None:
            print("interrupted", file=sys.stderr)
        return 130
    if died is not None:
        name = signal.Signals(died).name if died in signal.Signals._value2member_map_ else str(died)
        print(f"error: internal error, please report: the working process died of {name}"
              + (f"; removed {', '.join(removed)}" if removed else ""), file=sys.stderr)
        return 1
    return os.WEXITSTATUS(status) if os.WIFEXITED(status) else 1


def _clean(folders: Callable[[], Iterable[Path]]) -> list[str]:
    from fabricate.runfolder import clean_stale_parts

    removed = []
    for folder in folders():
        with contextlib.suppress(OSError):
            removed += [n.split(" ", 2)[1] for n in clean_stale_parts(Path(folder)) if n.startswith("removed ")]
    return removed
