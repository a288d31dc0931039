"""One table from exception classes to exit codes and the one line the user reads.

0 ok, 2 bad input (a file, mesh, config, path or argument), 3 tolerance not
reached, 4 export failed (a file could not be written: also a full disk),
1 internal error (a bug: "internal error, please report", traceback in a log
file), 130 interrupted, 141 output pipe closed (``fabricate measure M | head``:
silent, as for any Unix tool killed by SIGPIPE).
"""
from __future__ import annotations

import errno
import os
import sys

INTERRUPTED = 130
BROKEN_PIPE = 141

WRITE_FAILED = {errno.ENOSPC, errno.EDQUOT, errno.EIO, errno.EROFS, errno.EFBIG}
"""OSError numbers that mean the files could not be written (exit 4), not a bad path."""


def classify(exc: BaseException) -> tuple[int, str]:
    """``(exit code, one line)`` for an exception that ended a command ('' for no message)."""
    from .supervise import received

    if isinstance(exc, KeyboardInterrupt) or received():
        return INTERRUPTED, "interrupted"  # also what an interrupted import turned into
    errors = sys.modules.get("optimize.errors")  # not loaded: none of its errors was raised (fast)
    if errors is not None and isinstance(exc, errors.ConicalFabError):
        return exc.exit_code, f"error: {exc}"
    if isinstance(exc, BrokenPipeError):
        return BROKEN_PIPE, ""
    if isinstance(exc, OSError) and (exc.filename is not None or exc.errno in WRITE_FAILED):
        where = f"{exc.filename}: " if exc.filename is not None else ""
        if exc.filename2 is not None:
            where = f"{exc.filename} -> {exc.filename2}: "
        text = exc.strerror or str(exc)
        if exc.errno in WRITE_FAILED:
            return 4, f"error: {where}{text}; the files could not be written (nothing that looks complete was left)"
        return 2, f"error: {where}{text}"
    if isinstance(exc, UnicodeDecodeError):
        return 2, (f"error: an input file is not UTF-8 text ({exc.reason} at byte {exc.start}); "
                   "save it as UTF-8")
    from fabricate.app.crash import internal_error

    return 1, f"error: {internal_error(exc)}"


def quiet_broken_pipe() -> None:
    """After a closed pipe: point stdout at /dev/null so the exit flush does not raise again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass
