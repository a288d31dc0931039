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


def beside_name(target: Path) -> Path:
    """``<name>.failed-<UTC time>`` beside ``target`` (``-2``, ``-3``, ... when taken)."""
    stem = f"{target.name}.failed-{time.strftime('%Y%m%dT%H%M%SZ', time.gmtime())}"
    path, k = target.with_name(stem), 2
    while os.path.lexists(path):
        path, k = target.with_name(f"{stem}-{k}"), k + 1
    return path


def publish_run(tmp: Path, target: Path, previous: dict | None, exit_code: int) -> tuple[Path, str]:
    """Publish the finished run folder ``tmp``: at ``target``, or beside a passing result
    that a failing one must not replace.  Returns where it went and a note (empty if at target)."""
    if previous is not None and previous.get("exit_code") == 0 and exit_code != 0:
        dest = beside_name(target)
        publish_dir(tmp, dest)
        return dest, (f"the passing result in {target} was kept; this run (exit {exit_code}) was written "
                      f"beside it to {dest}")
    publish_dir(tmp, target)
    return target, ""


@contextlib.contextmanager
def run_lock(target: Path) -> Iterator[None]:
    """Hold an exclusive lock on writing ``target`` (``<parent>/.<name>.lock``, removed on release).

    Raises ConfigError (exit 2) when another process holds it, naming that process."""
    try:
        import fcntl
    except ImportError:  # not a POSIX system: no lock
        log.warning("%s: runs into this folder are not kept apart on this system (no fcntl)", target.parent)
        yield
        return

    path = target.with_name(f".{target.name}.lock")
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            os.close(fd)
            if exc.errno in (errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS):  # a file system without locks
                log.warning("%s: this file system cannot lock files (%s); runs into it are not kept apart",
                            target.parent, exc.strerror)
                with contextlib.suppress(OSError):
                    os.unlink(path)
                yield
                return
            if exc.errno not in (errno.EAGAIN, errno.EACCES):
                raise
            raise ConfigError(f"{target}: another fabricate run is writing this folder ({_holder(path)}); "
                              "this run stopped before doing any work: wait for that one to finish, or "
                              "choose another --out or name") from None
        try:  # the file we locked must still be the one at the path (a releaser unlinks it)
            same = os.path.samestat(os.fstat(fd), os.stat(path))
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, (json.dumps(owner_record()) + "\n").encode())
        yield
    finally:
        with contextlib.suppress(OSError):
            os.unlink(path)
        os.close(fd)


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
            remove_part(path)
            notes.append(f"removed {path} ({size / 1e6:.1f} MB), left by a run that ended without cleaning "
                         f"up (pid {rec.get('pid')}, started {rec.get('created_utc')})")
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
        if owner_gone(rec):
            remove_part(path)
            removed.append(str(path))
    _drop_free_locks(folder)
    return removed


def _empty_and_old(path: Path, age: float = 60.0) -> bool:
    try:
        return not any(path.iterdir()) and time.time() - path.stat().st_mtime > age
    except OSError:
        return False


def _drop_free_locks(folder: Path) -> None:
    """Remove lock files in ``folder`` that no process holds (left by a killed run)."""
    try:
        import fcntl
    except ImportError:
        return

    for path in sorted(folder.glob(".*.lock")):
        with contextlib.suppress(OSError):
            fd = os.open(path, os.O_RDWR)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                os.unlink(path)
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
