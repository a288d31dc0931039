"""Atomic file and folder writing: a failed run never leaves a file that looks complete.

Write to a temporary name in the target folder, then rename (``os.replace``
is atomic on one file system).  What is published gets the usual modes of the
process umask (``tempfile`` creates private 0600 files and 0700 folders).

A temporary folder (``.<name>.<random>.part``) holds an owner record
(:data:`PART_OWNER`: host, pid and the process start time) until it is
published, so that :func:`stale_parts` can tell the leftovers of a killed
process from the folder of a run still writing.
"""
from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import json
import logging
import os
import shutil
import socket
import tempfile
import time
from pathlib import Path
from typing import Iterator

from . import jsontext

log = logging.getLogger(__name__)

PART_OWNER = ".conical-fab-part.json"
"""The owner record inside a temporary folder (removed when the folder is published)."""


def umask() -> int:
    """The process umask, read without changing it where possible (threads may be writing files)."""
    with contextlib.suppress(OSError, ValueError):
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def public_mode(path: str | os.PathLike, folder: bool = False) -> None:
    """Give ``path`` the mode a plain ``open`` / ``mkdir`` would have (0666 / 0777 less the umask)."""
    os.chmod(path, (0o777 if folder else 0o666) & ~umask())


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; on success rename it to ``target``.

    On an exception the temporary file is removed and ``target`` is untouched.
    """
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part", dir=target.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        public_mode(tmp_path)
        os.replace(tmp_path, target)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        raise


@contextlib.contextmanager
def atomic_open(target: str | os.PathLike, mode: str = "w", **kwargs) -> Iterator:
    """``open`` a temporary file beside ``target``; rename it to ``target`` when closed cleanly."""
    with atomic_path(target) as tmp, open(tmp, mode, **kwargs) as fh:
        yield fh


# -- temporary folders and who owns them ---------------------------------------------------------
def _start_time(pid: int) -> str | None:
    """The start time of process ``pid`` (clock ticks since boot, Linux ``/proc``), None if unknown."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return text.rsplit(")", 1)[-1].split()[19]  # field 22; the name in (...) may hold spaces


def owner_record() -> dict:
    """``{"host", "pid", "start", "created_utc"}`` of this process."""
    return {"host": socket.gethostname(), "pid": os.getpid(), "start": _start_time(os.getpid()),
            "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}


def owner_alive(record: dict) -> bool | None:
    """Whether the process of an owner record still runs: None when it ran on another host."""
    if record.get("host") != socket.gethostname():
        return None
    pid = record.get("pid")
    if not isinstance(pid, int) or pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass  # exists, another user's
    start = _start_time(pid)
    return start is None or record.get("start") in (None, start)  # a reused pid has another start time


def read_owner(folder: Path) -> dict | None:
    """The owner record of a temporary folder, None if it has none (or it is unreadable)."""
    try:
        data = jsontext.loads((folder / PART_OWNER).read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def part_dir(target: str | os.PathLike) -> Path:
    """A new temporary folder ``.<name>.<random>.part`` beside ``target``, with this process's owner record."""
    target = Path(target)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".part", dir=target.parent))
    _write_owner(tmp)
    return tmp


def _write_owner(folder: Path) -> None:
    (folder / PART_OWNER).write_text(json.dumps(owner_record()) + "\n")


def stale_parts(folder: str | os.PathLike) -> list[tuple[Path, dict | None, bool | None]]:
    """Temporary folders ``.*.part`` in ``folder`` with their owner record and whether it is alive
    (None: on another host or no record)."""
    out = []
    with contextlib.suppress(OSError):
        for path in sorted(Path(folder).glob(".*.part")):
            if path.is_dir() and not path.is_symlink():
                rec = read_owner(path)
                out.append((path, rec, owner_alive(rec) if rec else None))
    return out


def remove_part(folder: Path) -> OSError | None:
    """Remove a temporary folder, its owner record last: a removal cut short (the process killed)
    leaves a folder that still says whose it was, so the next clean-up finishes it.

    Returns None when the folder is gone, else the error that kept something in it (permission, an
    immutable file, ...): all else is removed and the owner record stays."""
    error = None
    try:
        children = [c for c in folder.iterdir() if c.name != PART_OWNER]
    except FileNotFoundError:
        return None
    except OSError as exc:
        children, error = [], exc
    for child in children:
        try:
            if child.is_dir() and not child.is_symlink():
                shutil.rmtree(child, ignore_errors=True)   # all that can go, then why the rest cannot
                if os.path.lexists(child):
                    shutil.rmtree(child)
            else:
                child.unlink()
        except FileNotFoundError:
            pass
        except OSError as exc:
            error = error or exc
    if error is not None:
        return error
    with contextlib.suppress(FileNotFoundError):
        (folder / PART_OWNER).unlink()
    try:
        folder.rmdir()
    except FileNotFoundError:
        return None
    except OSError as exc:
        return exc
    return None


def folder_size(folder: Path) -> int:
    """Bytes of the files under ``folder`` (errors ignored)."""
    total = 0
    for root, _, files in os.walk(folder):
        for f in files:
            with contextlib.suppress(OSError):
                total += os.lstat(os.path.join(root, f)).st_size
    return total


# -- publishing a folder -------------------------------------------------------------------------
RENAME_EXCHANGE = 2
_libc = None


def exchange(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Swap two paths in one atomic step (Linux ``renameat2(RENAME_EXCHANGE)``); False when the
    system cannot (then nothing changed)."""
    global _libc
    if _libc is None:
        try:
            _libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
            _libc.renameat2  # noqa: B018 - glibc >= 2.28
        except (OSError, AttributeError):
            _libc = False
    if not _libc:
        return False
    AT_FDCWD = -100
    rc = _libc.renameat2(AT_FDCWD, os.fsencode(a), AT_FDCWD, os.fsencode(b), RENAME_EXCHANGE)
    if rc == 0:
        return True
    err = ctypes.get_errno()
    if err in (22, 38, 95):  # EINVAL, ENOSYS, EOPNOTSUPP: this file system cannot exchange
        return False
    raise OSError(err, os.strerror(err), str(b))


def publish_dir(tmp: Path, target: Path) -> tuple[Path, OSError] | None:
    """Put the complete folder ``tmp`` at ``target``, replacing what is there in one rename.

    The replaced folder is swapped into ``tmp`` (an owned temporary folder, so that a crash
    while removing it leaves a leftover :func:`stale_parts` recognises) and removed.
    Returns None, or when the replaced folder could not be removed: where it is (a temporary
    folder) and why, for the caller to tell (``target`` holds the new folder all the same).
    """
    with contextlib.suppress(FileNotFoundError):
        (tmp / PART_OWNER).unlink()
    public_mode(tmp, folder=True)
    if not os.path.lexists(target):
        os.rename(tmp, target)
        return None
    if exchange(tmp, target):
        old = tmp
    else:
        old = part_dir(target)
        os.rename(target, old / "old")
        os.rename(tmp, target)
    with contextlib.suppress(OSError):
        _write_owner(old)
    exc = remove_part(old)
    return None if exc is None else (old, exc)


@contextlib.contextmanager
def atomic_dir(target: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary folder beside ``target``; on success it replaces ``target``.

    An existing ``target`` is replaced only after the new one is complete; on
    an exception the temporary folder is removed and ``target`` is untouched.
    (Whether ``target`` may be replaced at all is the caller's decision.)
    """
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = part_dir(target)
    try:
        yield tmp
        leftover = publish_dir(tmp, target)
    except BaseException:
        remove_part(tmp)
        raise
    if leftover is not None:
        log.warning("%s: replaced, but the old folder could not be deleted (%s); it is left in %s",
                    target, leftover[1], leftover[0])
