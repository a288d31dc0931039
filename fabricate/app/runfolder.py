"""What a run may do to the folder it writes: never lose a user's files.

A finished run folder holds :data:`MARKER` (``.conical-fab-run.json``: tool
version, config hash, status, exit code and the size and modification time of
every file the run wrote).  A rerun

* writes into a new folder when ``<out>/<name>`` does not exist (or is empty);
* refuses (exit 2, nothing written) when it exists and is not a run folder of
  this tool, when files in it were added or changed since the run wrote it,
  or when it is a finished run and neither ``--force`` nor
  ``outputs.overwrite: true`` was given;
* otherwise replaces it in one atomic rename once the new run is complete,
  except that a result that misses a tolerance or fails its file check
  (exit 3 / 4) never replaces a passing one (exit 0): it is written beside it
  as ``<name>.failed-<UTC time>/`` and the summary says so.

One run at a time writes a given ``<out>/<name>``: :func:`run_lock` holds an
exclusive ``flock`` on ``<out>/.<name>.lock`` from the first check to the
final rename; a second run ends at once with a message naming the first.
Temporary folders of dead runs (owner process gone) are removed and named by
:func:`clean_stale_parts`.

A run deletes only what it made: a lock file is removed only when it holds a
record this tool wrote (:func:`lock_is_ours`) and neither a run (``flock``) nor
another program (``lockf``) holds it; a user's ``.notes.lock`` is never
touched, and one in the way of a run's lock stops the run (exit 2).  An earlier
run that is replaced but cannot be deleted is moved beside the new one as
``<name>.old-<UTC time>/`` and named (:func:`publish_run`).
"""
from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import logging
import os
import time
from pathlib import Path
from typing import Iterator

from optimize.atomic import (PART_OWNER, folder_size, owner_alive, owner_record, part_dir, publish_dir,
                             read_owner, remove_part, stale_parts)
from optimize import jsontext
from optimize.errors import ConfigError

log = logging.getLogger(__name__)

MARKER = ".conical-fab-run.json"
SHOWN = 5  # file names quoted in a message


def config_hash(config) -> str:
    """sha256 of the configuration as run (defaults filled in), hex."""
    text = json.dumps(config.as_dict(), sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def manifest(folder: Path) -> dict[str, list[int]]:
    """``{relative path: [size, mtime_ns]}`` of every file under ``folder`` but the marker (and the
    temporary folder's owner record, removed when it is published)."""
    out = {}
    for path in sorted(folder.rglob("*")):
        rel = path.relative_to(folder).as_posix()
        if rel not in (MARKER, PART_OWNER) and (path.is_file() or path.is_symlink()):
            st = path.lstat()
            out[rel] = [st.st_size, st.st_mtime_ns]
    return out


def write_marker(folder: Path, facts: dict) -> None:
    """Write :data:`MARKER` into ``folder`` (last, so the manifest covers every other file)."""
    from .. import __version__

    data = {"tool": "conical-fab", "version": __version__,
            "finished_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), **facts,
            "files": manifest(folder)}
    (folder / MARKER).write_text(json.dumps(data, indent=1) + "\n")


def read_marker(folder: Path) -> dict | None:
    try:
        data = jsontext.loads((folder / MARKER).read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) and data.get("tool") == "conical-fab" else None


def changed_files(folder: Path, marker: dict) -> list[str]:
    """Files under ``folder`` the run did not write (``name (added)``) or that changed since
    (``name (changed)``); files the user deleted lose nothing and are not listed."""
    written = marker.get("files") or {}
    out = []
    for rel, facts in manifest(folder).items():
        if rel not in written:
            out.append(f"{rel} (added)")
        elif list(written[rel]) != facts:
            out.append(f"{rel} (changed)")
    return out


def _listed(items: list[str]) -> str:
    return ", ".join(items[:SHOWN]) + (f" and {len(items) - SHOWN} more" if len(items) > SHOWN else "")


def check_target(target: Path, force: bool, flag: str = "--force (or outputs.overwrite: true in the config)",
                 ) -> dict | None:
    """May a run write ``target``?  The marker of the finished run there (None: nothing there).

    force : replace an earlier finished run (``flag`` names the option that says so, in the message).
    Raises ConfigError (exit 2) naming the folder and why not.
    """
    if not os.path.lexists(target):
        return None
    if target.is_symlink() or not target.is_dir():
        raise ConfigError(f"{target}: exists and is not a folder (expected a new name or an earlier run "
                          "folder of conical-fab); nothing was written: choose another --out or name")
    try:
        empty = not any(target.iterdir())
    except OSError as exc:
        raise ConfigError(f"{target}: cannot be read ({exc.strerror}); nothing was written") from None
    if empty:
        return None
    marker = read_marker(target)
    if marker is None:
        raise ConfigError(f"{target}: exists and is not a run folder of conical-fab (no {MARKER}); it is "
                          "left as it is and nothing was written: choose another --out or name, or move "
                          "the folder away")
    changed = changed_files(target, marker)
    if changed:
        raise ConfigError(f"{target}: holds files conical-fab did not write: {_listed(changed)}; the "
                          "folder is left as it is and nothing was written: move those files out, or "
                          "choose another --out or name")
    if not force:
        raise ConfigError(f"{target}: holds an earlier run ({marker.get('status')}, exit code "
                          f"{marker.get('exit_code')}, finished {marker.get('finished_utc')}); it is "
                          f"kept and nothing was written: rerun with {flag} to replace it, or choose "
                          "another --out or name")
    return marker


def beside_name(target: Path, what: str = "failed") -> Path:
    """``<name>.<what>-<UTC time>`` beside ``target`` (``-2``, ``-3``, ... when taken)."""
    stem = f"{target.name}.{what}-{time.strftime('%Y%m%dT%H%M%SZ', time.gmtime())}"
    path, k = target.with_name(stem), 2
    while os.path.lexists(path):
        path, k = target.with_name(f"{stem}-{k}"), k + 1
    return path


def publish_run(tmp: Path, target: Path, previous: dict | None, exit_code: int) -> tuple[Path, str]:
    """Publish the finished run folder ``tmp``: at ``target``, or beside a passing result
    that a failing one must not replace.  Returns where it went and a note for the user (one line,
    empty if at target and nothing is left over)."""
    if previous is not None and previous.get("exit_code") == 0 and exit_code != 0:
        dest = beside_name(target)
        publish_dir(tmp, dest)
        return dest, (f"the passing result in {target} was kept; this run (exit {exit_code}) was written "
                      f"beside it to {dest}")
    leftover = publish_dir(tmp, target)
    return target, "" if leftover is None else _leftover_note(target, *leftover)


def _leftover_note(target: Path, old: Path, exc: OSError) -> str:
    """Move what is left of the replaced run at ``old`` (a temporary folder) beside ``target`` under a
    visible name, and say so: which run, where it is now, why it is there."""
    where = beside_name(target, "old")
    try:
        (old / PART_OWNER).unlink(missing_ok=True)      # no longer a temporary folder: the user's to delete
        os.rename(old, where)
    except OSError:
        where = old
    with contextlib.suppress(TypeError, ValueError):   # the file that stayed, under its new name
        exc.filename = str(where / Path(exc.filename).relative_to(old))
    return (f"the earlier run in {target} was replaced but could not be deleted ({_why(exc)}); "
            f"what is left of it is in {where}: delete it when you can")


def _why(exc: OSError) -> str:
    return f"{exc.strerror or exc}: {exc.filename}" if exc.filename else str(exc.strerror or exc)


LOCK_TOOL = "conical-fab-lock"
"""The ``tool`` of the record in a lock file this tool wrote (:func:`lock_is_ours`)."""
LOCK_MAX = 4096  # bytes: a lock record is about 150; a longer file is not one


def lock_is_ours(text: bytes) -> bool:
    """Whether ``text`` (a lock file's content) is a record this tool wrote: ``{"tool":
    "conical-fab-lock", "pid", "host", ...}``, or the owner record alone of earlier versions
    (exactly ``host``, ``pid``, ``start``, ``created_utc``)."""
    try:
        rec = jsontext.loads(text.decode())
    except (UnicodeDecodeError, ValueError):
        return False
    if not isinstance(rec, dict):
        return False
    return ((rec.get("tool") == LOCK_TOOL and isinstance(rec.get("pid"), int) and "host" in rec)
            or sorted(rec) == ["created_utc", "host", "pid", "start"])


def _read_lock(fd: int) -> bytes:
    return os.pread(fd, LOCK_MAX + 1, 0)


@contextlib.contextmanager
def run_lock(target: Path) -> Iterator[None]:
    """Hold an exclusive lock on writing ``target`` (``<parent>/.<name>.lock``, removed on release).

    Raises ConfigError (exit 2) when another process holds it, naming that process, or when a file
    of that name that this tool did not write is in the way (it is left as it is)."""
    try:
        import fcntl
    except ImportError:  # not a POSIX system: no lock
        log.warning("%s: runs into this folder are not kept apart on this system (no fcntl)", target.parent)
        yield
        return

    path = target.with_name(f".{target.name}.lock")
    fd = _take_lock(fcntl, path, target)
    if fd is None:
        yield
        return
    try:
        yield
    finally:
        with contextlib.suppress(OSError):
            if os.path.samestat(os.fstat(fd), os.lstat(path)):
                os.unlink(path)
        os.close(fd)


def _take_lock(fcntl, path: Path, target: Path) -> int | None:
    """The descriptor of the lock file ``path``, flocked by this process and holding its record; None
    when the file system cannot lock.  Whatever stops it (ConfigError, Ctrl-C) leaves no file it made."""
    record = (json.dumps({"tool": LOCK_TOOL, "run": target.name, **owner_record()}) + "\n").encode()
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o666)
        except OSError as exc:
            raise ConfigError(f"{path}: the lock file of this run cannot be created or opened ({exc.strerror}; "
                              "expected a new name or a lock file of conical-fab); nothing was written: "
                              "move that file away, or choose another --out or name") from None
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                if exc.errno in (errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS):  # a file system without locks
                    log.warning("%s: this file system cannot lock files (%s); runs into it are not kept apart",
                                target.parent, exc.strerror)
                    with contextlib.suppress(OSError):
                        if not _read_lock(fd).strip():
                            os.unlink(path)  # the empty file just made; anything else is not ours to remove
                    os.close(fd)
                    return None
                if exc.errno not in (errno.EAGAIN, errno.EACCES):
                    raise
                raise ConfigError(f"{target}: another fabricate run is writing this folder ({_holder(path)}); "
                                  "this run stopped before doing any work: wait for that one to finish, or "
                                  "choose another --out or name") from None
            try:  # the file we locked must still be the one at the path (a releaser unlinks it)
                same = os.path.samestat(os.fstat(fd), os.lstat(path))
            except FileNotFoundError:
                same = False
            if same:
                text = _read_lock(fd)
                if text.strip() and not lock_is_ours(text):
                    raise ConfigError(f"{path}: a file of the name of this run's lock file, not written by "
                                      f"conical-fab ({len(text)}{'+' if len(text) > LOCK_MAX else ''} bytes), is in "
                                      "the way; it is left as it is and nothing was written: move it away, or "
                                      "choose another --out or name")
                os.ftruncate(fd, 0)
                os.write(fd, record)
                return fd
        except BaseException:
            _remove_if_free(fcntl, fd, path, empty=True)
            os.close(fd)
            raise
        os.close(fd)


def _remove_if_free(fcntl, fd: int, path: Path, empty: bool = False) -> None:
    """Unlink the lock file ``path`` (open as ``fd``, read-write) when it holds a record this tool wrote
    (or nothing, with ``empty``: one just made) and no run holds it (``flock``) nor another program
    (a POSIX ``lockf`` / ``fcntl`` lock; such locks of this very process are not seen)."""
    with contextlib.suppress(OSError):
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        fcntl.lockf(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        text = _read_lock(fd)
        if (lock_is_ours(text) or (empty and not text.strip())) and os.path.samestat(os.fstat(fd), os.lstat(path)):
            os.unlink(path)


def _holder(path: Path) -> str:
    try:
        rec = jsontext.loads(path.read_text())
        return f"pid {rec['pid']} on {rec['host']}, since {rec['created_utc']}"
    except (OSError, ValueError, KeyError, TypeError):
        return "a process that just started"


def clean_stale_parts(folder: Path, name: str | None = None) -> list[str]:
    """Remove the temporary folders in ``folder`` whose owner process is gone; one note for each
    removed, and for each of ``name``'s that has no owner record (left alone: whose is it?)."""
    notes = []
    for path, rec, alive in stale_parts(folder):
        if rec is None and _empty_and_old(path):
            remove_part(path)  # nothing to lose, and no run takes a minute to write its owner record
            continue
        if rec is not None and alive is not None and owner_gone(rec):
            size = folder_size(path)
            exc = remove_part(path)
            left = (f"removed {path} ({size / 1e6:.1f} MB)" if exc is None else
                    f"could not remove {path} ({folder_size(path) / 1e6:.1f} MB left: {_why(exc)})")
            notes.append(f"{left}, left by a run that ended without cleaning up (pid {rec.get('pid')}, "
                         f"started {rec.get('created_utc')})")
        elif rec is None and name is not None and path.name.startswith(f".{name}.") and read_owner(path) is None:
            notes.append(f"left alone: {path} ({folder_size(path) / 1e6:.1f} MB), a temporary folder with no "
                         "owner record (an older version's?); remove it when no run is writing there")
        elif rec is not None and alive is None and name is not None and path.name.startswith(f".{name}."):
            notes.append(f"left alone: {path}, being written by pid {rec.get('pid')} on {rec.get('host')} "
                         "(cannot tell from here whether it still runs)")
    _drop_free_locks(folder)
    return notes


def owner_gone(record: dict) -> bool:
    """Whether the process of an owner record (``optimize.atomic.owner_record``) has ended: no such
    process on this host, a reused pid, or only its zombie (killed, not yet reaped).  False for a
    record of another host (cannot tell from here)."""
    alive = owner_alive(record)
    if alive is None:
        return False
    if not alive:
        return True
    try:
        state = Path(f"/proc/{record['pid']}/stat").read_text().rsplit(")", 1)[-1].split()[0]
    except (OSError, IndexError):
        return False
    return state in ("Z", "X")


def remove_dead_parts(folder: Path, wait: float = 0.0) -> list[str]:
    """Remove the temporary folders in ``folder`` whose owner process on this host is gone (waiting up
    to ``wait`` seconds for killed ones to go) and the lock files nobody holds; the removed folders.
    The supervisor of ``fabricate run`` / ``batch`` calls this after it killed its work."""
    removed = []
    for path, rec, alive in stale_parts(folder):
        if rec is None or alive is None:
            continue  # no owner record, or another host's: not ours to judge
        deadline = time.monotonic() + wait
        while not owner_gone(rec) and time.monotonic() < deadline:
            time.sleep(0.02)
        if owner_gone(rec) and remove_part(path) is None:
            removed.append(str(path))
    _drop_free_locks(folder)
    return removed


def _empty_and_old(path: Path, age: float = 60.0) -> bool:
    try:
        return not any(path.iterdir()) and time.time() - path.stat().st_mtime > age
    except OSError:
        return False


def _drop_free_locks(folder: Path) -> None:
    """Remove the lock files in ``folder`` that killed runs left, and only those: files holding a
    record this tool wrote (:func:`lock_is_ours`) that no process holds (:func:`_remove_if_free`)."""
    try:
        import fcntl
    except ImportError:
        return

    for path in sorted(folder.glob(".*.lock")):
        if path.is_symlink() or not path.is_file():
            continue
        with contextlib.suppress(OSError):
            fd = os.open(path, os.O_RDWR | os.O_NOFOLLOW | os.O_NONBLOCK)
            try:
                _remove_if_free(fcntl, fd, path)
            finally:
                os.close(fd)


def make_parent(target: Path, what: str = "--out") -> None:
    """Create the parent of ``target``; ConfigError naming the path (as the option ``what``) when it
    cannot be."""
    parent = target.parent
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise ConfigError(f"{what} {parent}: a file is in the way (expected a folder or a new path)") from None
    except OSError as exc:
        raise ConfigError(f"{what} {parent}: cannot create the folder ({exc.strerror})") from None
    if not parent.is_dir():
        raise ConfigError(f"{what} {parent}: is not a folder (expected a folder or a new path)")


def new_part(target: Path) -> Path:
    """The temporary folder of a run at ``target`` (ConfigError when the name cannot be created)."""
    try:
        return part_dir(target)
    except OSError as exc:
        raise ConfigError(f"{target}: cannot create a folder there ({exc.strerror})") from None
