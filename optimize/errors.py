"""The exception hierarchy of the package.

Every error carries the facts: which file, line or key, the value found and
what was expected.  The CLI turns each into one line and an exit code.
"""
from __future__ import annotations

import contextlib
import errno
import os
import shutil
from typing import Iterator


class ConicalFabError(Exception):
    """Base class of every error raised on purpose by this package."""

    exit_code = 1


class MeshError(ConicalFabError, ValueError):
    """A mesh file or mesh array that cannot be used (bad input: exit 2)."""

    exit_code = 2


class ConfigError(ConicalFabError, ValueError):
    """A configuration file or value that is not valid (bad input: exit 2)."""

    exit_code = 2


class ConvergenceError(ConicalFabError, RuntimeError):
    """An optimization that did not reach its tolerance (exit 3)."""

    exit_code = 3


class ExportError(ConicalFabError, RuntimeError):
    """A file could not be built or written (exit 4)."""

    exit_code = 4


DISK_FULL = {errno.ENOSPC: "disk full", errno.EDQUOT: "disk quota exceeded",
             errno.EFBIG: "file too large for the file system"}
"""OSError numbers of a write the disk has no room for, and how the one line begins."""


def write_error(path: str | os.PathLike, what: str, exc: OSError, needed: int | None = None) -> ExportError:
    """The one-line ExportError (exit 4) for ``exc``, raised while writing ``what`` (``"STL file"``) to
    ``path``: ``<path>: cannot write the <what> (<reason>)``, and when the disk is full (or a quota or
    the file size limit is reached) it begins by saying so and names the bytes ``needed`` (when
    known) and those free on that disk."""
    text = f"{path}: cannot write the {what} ({exc.strerror or exc}"
    head = DISK_FULL.get(exc.errno)
    if head is None:
        return ExportError(text + ")")
    sizes = [f"{_size(needed)} needed"] if needed else []
    if exc.errno == errno.ENOSPC:
        with contextlib.suppress(OSError, ValueError):
            folder = os.path.dirname(os.path.abspath(path))
            while not os.path.isdir(folder) and os.path.dirname(folder) != folder:
                folder = os.path.dirname(folder)
            sizes.append(f"{_size(shutil.disk_usage(folder).free)} free there")
    return ExportError(f"{head} writing {text}{'; ' if sizes else ''}{', '.join(sizes)})")


def _size(n: int) -> str:
    return f"{n / 1e9:.1f} GB" if n >= 1e9 else f"{n / 1e6:.1f} MB" if n >= 1e5 else f"{n / 1e3:.1f} kB"


def c_errno(value: int | None = None) -> int:
    """The C library's ``errno`` of this thread (glibc; 0 where it cannot be read), set to ``value``
    first when given: why a native writer (rhino3dm, OpenCASCADE) that returns only "failed" failed.
    Set it to 0 before the native call and read it right after."""
    global _errno_location
    if _errno_location is None:
        import ctypes

        try:
            _errno_location = ctypes.CDLL(None).__errno_location
            _errno_location.restype = ctypes.POINTER(ctypes.c_int)
        except (OSError, AttributeError):
            _errno_location = False
    if not _errno_location:
        return 0
    cell = _errno_location()
    if value is not None:
        cell[0] = value
    return cell[0]


_errno_location = None


@contextlib.contextmanager
def writing(path: str | os.PathLike, what: str, needed: int | None = None) -> Iterator[None]:
    """Turn an OSError in the block into :func:`write_error`'s ExportError, raised from it (so that
    the run sees the disk refusing: nothing more is written)."""
    try:
        yield
    except OSError as exc:
        raise write_error(path, what, exc, needed) from exc
