"""The traceback of an internal error goes to a log file, not on the user's screen."""
from __future__ import annotations

import os
import sys
import tempfile
import time
import traceback
from pathlib import Path

from .. import __version__


def crash_log(exc: BaseException, what: str = "") -> Path | None:
    """Write ``exc``'s traceback (with the command line and versions) to a new file in
    ``<temp>/conical-fab/``; its path, or None when even that cannot be written."""
    try:
        folder = Path(tempfile.gettempdir()) / "conical-fab"
        folder.mkdir(parents=True, exist_ok=True)
        fd, name = tempfile.mkstemp(prefix=f"crash-{time.strftime('%Y%m%dT%H%M%S')}-{os.getpid()}-",
                                    suffix=".log", dir=folder)
        with os.fdopen(fd, "w") as fh:
            fh.write(f"conical-fab {__version__}, Python {sys.version.split()[0]}, {sys.platform}\n")
            fh.write(f"command: {' '.join(sys.argv)}\n")
            if what:
                fh.write(f"while: {what}\n")
            fh.write("".join(traceback.format_exception(type(exc), exc, exc.__traceback__)))
        return Path(name)
    except OSError:
        return None


def internal_error(exc: BaseException, what: str = "") -> str:
    """One line for an internal error: what it was and where its traceback is."""
    path = crash_log(exc, what)
    where = f"traceback in {path}" if path else "no log could be written"
    return f"internal error, please report: {type(exc).__name__}: {exc} ({where})"
