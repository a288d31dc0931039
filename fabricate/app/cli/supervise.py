"""Ctrl-C ends a command within two seconds, at any moment, with exit 130 and no traceback.

Python handles a signal only between bytecodes: inside one long call into
OpenCASCADE, MKL or numba it would wait until that call returns (a STEP
read-back of a large model takes a minute).  So the ``fabricate`` command runs
its work in a forked child in a process group of its own and stays a small
supervisor: it forwards SIGINT / SIGTERM / SIGHUP to the child (which turns
the first into KeyboardInterrupt and unwinds, removing its temporary folders;
a batch stops its workers), and when the group has not ended :data:`GRACE` seconds later it kills
it (batch workers included) and removes the temporary folders the killed
processes left (:func:`fabricate.app.runfolder.clean_stale_parts`).
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

GRACE = 1.0
"""Seconds the work may take to unwind after a signal before it is killed."""
FORWARDED = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))


_RECEIVED: list[int] = []


def received() -> int | None:
    """The signal :func:`interrupt_handler` received in this process, if any."""
    return _RECEIVED[0] if _RECEIVED else None


def interrupt_handler(signum, frame):
    """In the working process: the first signal unwinds (KeyboardInterrupt); later ones are ignored
    so that they cannot break off the clean-up the first one started."""
    _RECEIVED.append(signum)
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
    parent = os.getpid()
    pid = os.fork()
    if pid == 0:  # the child: do the work, never return into the caller
        code = 1
        try:
            os.setpgid(0, 0)
            _die_with(parent)
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


def _die_with(parent: int) -> None:
    """Linux: the child is killed when the supervisor dies (``kill -9`` of it, or of its process
    group, which the child left): nothing may go on writing unwatched."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if os.getppid() != parent:  # it died before the request was made
        os._exit(1)


def _watch(pid: int, folders: Callable[[], Iterable[Path]]) -> int:
    with contextlib.suppress(OSError):
        os.setpgid(pid, pid)  # also here: no window in which a signal reaches the old group only
    state = {"signal": None, "deadline": None}

    def forward(signum, frame):
        if state["signal"] is None:
            state["deadline"] = time.monotonic() + GRACE
        state["signal"] = signum
        with contextlib.suppress(OSError):
            os.kill(pid, signum)  # the child only: a batch stops its own workers

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
    """Remove the temporary folders under ``folders`` whose owner process (on this host) is gone,
    waiting a second for killed ones to go, and the lock files no process holds; the removed
    folders (:func:`fabricate.app.runfolder.remove_dead_parts`, the one owner-record check)."""
    from fabricate.app.runfolder import remove_dead_parts  # light: no solver, no CAD kernel

    removed: list[str] = []
    for folder in folders():
        removed += remove_dead_parts(Path(folder), wait=1.0)
    return removed
