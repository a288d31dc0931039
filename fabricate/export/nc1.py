"""DSTV NC1 files for steel CNC lines: one ``<id>.nc1`` per beam plate and per hub tube, in a ``nc1/`` folder.

A beam welded from plates (tee, I, RHS) gets one file per plate (``B0012.1.nc1`` the web ...): a
plate line cuts each from flat stock with its own contour and end cuts; the steel cut list says
which beam and member each is.

Written from the DSTV standard ("Standard Description for Information
Exchange in Steel Construction", NC data interface), ASCII, one value per
line, millimetres and degrees:

``ST`` header block, after a ``**`` comment line, 24 lines in this order:
order, drawing, phase, piece (the part id), steel grade, quantity, profile
(``PL<thickness>``), profile code (``B``: plate), length (x extent of the
contour), profile height (y extent: the plate's width), flange width and
flange thickness (0: a plate has none), web thickness (the plate
thickness), radius (0), weight per metre (kg/m: the part's weight over its
length), painting surface per metre (m²/m: both faces and the edges), web
start cut and web end cut (deg from square, in the plate plane), flange
start cut and flange end cut (deg from square, across the thickness: the
bevel), four text lines (the run name, the kind, the mesh edge, the
neighbours).  For a plate the outer contour below defines the cut; the cut
angles are given for the operator.

``AK`` outer contour of the front face ``v`` (the outline the DXF draws on
layer CUT, the same frame turned so that x runs along the beam): the first
line carries the face flag, each line ``x y radius`` (radius 0: straight),
the contour closed by repeating its first point.  ``SI`` marks the id on
the face; ``EN`` ends the file.

A hub tube (``N0001.1``, the tube of a ``parts.node.hub: tube``) is a round tube cut square to
length from a circular hollow section: profile ``RO<D>x<wall>``, profile code ``RO``, length (the
cut between the caps), profile height (the outside diameter ``D``: the model's ``K``-gon is drawn
round it), flange width 0, flange thickness and web thickness (both the wall), radius 0, weight per
metre (the model's tube weight over its length, as the BOM), painting surface per metre (the
outside, ``pi D``), all four cuts 0 (square ends, normal to the node axis); no contour (the
section and the length define the cut), ``SI`` the id at mid-length.

The reader that checks these files (:mod:`fabricate.export.nc1_read`) is written
separately from this writer, from the same description.
"""
from __future__ import annotations

import contextlib
import itertools
import os
import secrets
import time
from pathlib import Path

import numpy as np

from optimize.atomic import atomic_dir, umask
from optimize.errors import ExportError, write_error

NUM = "{:10.3f}"


def contour(group, i: int) -> np.ndarray:
    """(k, 2) the flat outline of part ``i`` with its lower-left corner at the origin, x along the length."""
    Q = np.asarray(group.flat[i], dtype=float)
    if np.ptp(Q[:, 1]) > np.ptp(Q[:, 0]):  # x along the longer side
        Q = np.stack([Q[:, 1], -Q[:, 0]], axis=1)
    return Q - Q.min(axis=0)


def _signed_max(pair) -> float:
    """The value of larger magnitude of a pair (an end's bevel on its two sides), with its sign."""
    pair = np.asarray(pair, dtype=float)
    return float(pair[np.argmax(np.abs(pair))])


def nc1_text(group, i: int, *, order: str, grade: str, density: float, angles: dict) -> str:
    """The NC1 file of plate ``i`` of ``group`` (a beam group); ``angles``: the group's
    :func:`fabricate.export.schedules.beam_angles` (the steel cut list's end cuts)."""
    Q = contour(group, i)
    length, height = float(Q[:, 0].max()), float(Q[:, 1].max())
    t = float(group.thickness_mm[i])
    weight = float(group.volume_mm3[i]) * density * 1e-9
    perimeter = float(np.linalg.norm(np.roll(Q, -1, axis=0) - Q, axis=1).sum())
    paint = (2.0 * float(group.area_mm2[i]) + perimeter * t) * 1e-6 / (length * 1e-3)
    web = angles["mitre"][i]
    bevel = (_signed_max(angles["end_bevel"][i, 0]), _signed_max(angles["end_bevel"][i, 1]))
    pid = group.ids[i]
    head = [order, "conical-fab", "1", pid, grade, "1", f"PL{t:g}", "B"]
    numbers = [length, height, 0.0, 0.0, t, 0.0, weight / (length * 1e-3), paint, web[0], web[1],
               bevel[0], bevel[1]]
    texts = [order, group.member or group.kind, f"mesh edge {int(group.element[i])}", " ".join(group.neighbours[i])[:60]]
    lines = ["ST", f"** {pid}.nc1 written by conical-fab"]
    lines += [f"  {v}" for v in head] + ["  " + NUM.format(v).strip() for v in numbers] + [f"  {v}" for v in texts]
    lines.append("AK")
    closed = np.vstack([Q, Q[:1]])
    for j, (x, y) in enumerate(closed.tolist()):
        lines.append(("  v " if j == 0 else "    ") + f"{NUM.format(x)} {NUM.format(y)} {NUM.format(0.0)}")
    cx, cy = Q.mean(axis=0)
    lines += ["SI", f"  v {NUM.format(cx)} {NUM.format(cy)} {NUM.format(0.0)} 10 {pid}", "EN", ""]
    return "\n".join(lines)


def nc1_tube_text(group, i: int, *, order: str, grade: str, density: float) -> str:
    """The NC1 file of hub tube ``i`` of ``group`` (a node group of member ``tube``, vertices outer lower
    ring ``0..K-1`` first: :func:`fabricate.cad.hubs.tube_faces`)."""
    V = np.asarray(group.vertices[i], dtype=float)
    k = V.shape[0] // 4
    ring = V[:k]
    diameter = 2.0 * float(np.linalg.norm(ring - ring.mean(axis=0), axis=1).mean())
    wall = float(group.thickness_mm[i])
    length = float(group.length_mm[i])
    weight = float(group.volume_mm3[i]) * density * 1e-9
    pid = group.ids[i]
    head = [order, "conical-fab", "1", pid, grade, "1", f"RO{diameter:g}x{wall:g}", "RO"]
    numbers = [length, diameter, 0.0, wall, wall, 0.0, weight / (length * 1e-3), np.pi * diameter * 1e-3,
               0.0, 0.0, 0.0, 0.0]
    texts = [order, "hub tube", f"mesh vertex {int(group.element[i])}", " ".join(group.neighbours[i])[:60]]
    lines = ["ST", f"** {pid}.nc1 written by conical-fab"]
    lines += [f"  {v}" for v in head] + ["  " + NUM.format(v).strip() for v in numbers] + [f"  {v}" for v in texts]
    lines += ["SI", f"  v {NUM.format(0.5 * length)} {NUM.format(0.5 * diameter)} {NUM.format(0.0)} 10 {pid}",
              "EN", ""]
    return "\n".join(lines)


def _bevel_max(pair: np.ndarray) -> np.ndarray:
    """(p,) :func:`_signed_max` of every row of ``pair (p, 2)``: the first on a tie, a NaN as argmax finds it."""
    a, b = pair[:, 0], pair[:, 1]
    second = (np.abs(b) > np.abs(a)) | (np.isnan(b) & ~np.isnan(a))
    return np.where(second, b, a)


def _template(k: int | None) -> str:
    """The ``%`` template of one file (LF line ends): a plate with a contour of ``k`` corners
    (``k + 1`` lines, closed), or a tube (``k`` None: no contour)."""
    st = ["ST", "** %s.nc1 written by conical-fab", "  %s", "  conical-fab", "  1", "  %s", "  %s", "  1"]
    if k is None:
        st += ["  RO%gx%g", "  RO"] + ["  %.3f"] * 12 + ["  %s", "  hub tube", "  mesh vertex %d", "  %s"]
    else:
        st += ["  PL%g", "  B"] + ["  %.3f"] * 12 + ["  %s", "  %s", "  mesh edge %d", "  %s", "AK"]
        st += ["  v %10.3f %10.3f      0.000"] + ["    %10.3f %10.3f      0.000"] * k
    return "\n".join(st + ["SI", "  v %10.3f %10.3f      0.000 10 %s", "EN", ""])


def _neighbours(group) -> list[str]:
    return [" ".join(n)[:60] for n in group.neighbours]


def nc1_texts(group, *, order: str, grade: str, density: float, angles: dict) -> list[str]:
    """:func:`nc1_text` of every plate of ``group`` (the same text): the numbers of the whole group at
    once, ``flat (p, k, 2)`` turned and moved as :func:`contour` does each part."""
    F = np.asarray(group.flat, dtype=float)                                  # (p, k, 2)
    turn = np.ptp(F[:, :, 1], axis=1) > np.ptp(F[:, :, 0], axis=1)
    F = np.where(turn[:, None, None], np.stack([F[:, :, 1], -F[:, :, 0]], axis=2), F)
    Q = F - F.min(axis=1, keepdims=True)
    length, height = Q[:, :, 0].max(axis=1), Q[:, :, 1].max(axis=1)
    t = np.asarray(group.thickness_mm, dtype=float)
    weight = np.asarray(group.volume_mm3, dtype=float) * density * 1e-9
    perimeter = np.linalg.norm(np.roll(Q, -1, axis=1) - Q, axis=2).sum(axis=1)
    paint = (2.0 * np.asarray(group.area_mm2, dtype=float) + perimeter * t) * 1e-6 / (length * 1e-3)
    web = np.asarray(angles["mitre"], dtype=float)
    bevel = np.asarray(angles["end_bevel"], dtype=float)
    zero = np.zeros(len(t))
    numbers = np.stack([length, height, zero, zero, t, zero, weight / (length * 1e-3), paint, web[:, 0], web[:, 1],
                        _bevel_max(bevel[:, 0]), _bevel_max(bevel[:, 1])], axis=1).tolist()
    closed = np.concatenate([Q, Q[:, :1]], axis=1).reshape(len(t), -1).tolist()   # (p, 2 (k + 1))
    centre = Q.mean(axis=1).tolist()
    template, member = _template(Q.shape[1]), group.member or group.kind
    return [template % (pid, order, pid, grade, th, *num, order, member, int(el), nb, *xy, *c, pid)
            for pid, th, num, el, nb, xy, c in zip(group.ids, t.tolist(), numbers, group.element.tolist(),
                                                   _neighbours(group), closed, centre)]


def nc1_tube_texts(group, *, order: str, grade: str, density: float) -> list[str]:
    """:func:`nc1_tube_text` of every tube of ``group`` (the same text), the numbers of the group at once."""
    V = np.asarray(group.vertices, dtype=float)                               # (p, nv, 3)
    ring = V[:, :V.shape[1] // 4]
    diameter = 2.0 * np.linalg.norm(ring - ring.mean(axis=1, keepdims=True), axis=2).mean(axis=1)
    wall = np.asarray(group.thickness_mm, dtype=float)
    length = np.asarray(group.length_mm, dtype=float)
    weight = np.asarray(group.volume_mm3, dtype=float) * density * 1e-9
    zero = np.zeros(len(wall))
    numbers = np.stack([length, diameter, zero, wall, wall, zero, weight / (length * 1e-3), np.pi * diameter * 1e-3,
                        zero, zero, zero, zero], axis=1).tolist()
    mark = np.stack([0.5 * length, 0.5 * diameter], axis=1).tolist()
    template = _template(None)
    return [template % (pid, order, pid, grade, d, w, *num, order, int(el), nb, *m, pid)
            for pid, d, w, num, el, nb, m in zip(group.ids, diameter.tolist(), wall.tolist(), numbers,
                                                 group.element.tolist(), _neighbours(group), mark)]


class _Files:
    """Atomic files in one folder with few system calls: each written under a temporary name of its own
    beside it (``.<name>.<token>.part``, created exclusively, so no other file is touched), then renamed
    to its name; removed on failure.  ``staged``: the folder is a new one of this writer's that is put
    in place whole (:func:`optimize.atomic.atomic_dir`): each file is created under its name at once.
    The mode: 0666 less the umask, as ``open`` creates it (checked on the first file; set on every file
    where the folder's ACL makes it differ)."""

    FLAGS = (os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_NOFOLLOW", 0)
             | getattr(os, "O_BINARY", 0))

    def __init__(self, folder: Path, mode: int, staged: bool = False):
        self.folder, self.mode, self.chmod, self.staged = os.fspath(folder), mode, None, staged
        self.token = secrets.token_hex(6)

    def write(self, name: str, data: bytes) -> None:
        target = os.path.join(self.folder, name)
        if self.staged:   # a new folder of this writer's, published whole: each file under its name at once
            fd = os.open(target, self.FLAGS, 0o666)
            try:
                self._fill(fd, data)
            finally:
                os.close(fd)
            return
        while True:
            tmp = os.path.join(self.folder, f".{name}.{self.token}.part")
            try:
                fd = os.open(tmp, self.FLAGS, 0o666)
                break
            except FileExistsError:        # a leftover of another run with the same token: a new one
                self.token = secrets.token_hex(6)
        try:
            try:
                self._fill(fd, data)
            finally:
                os.close(fd)
            os.replace(tmp, target)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            raise

    def _fill(self, fd: int, data: bytes) -> None:
        if self.chmod is None:
            self.chmod = os.fstat(fd).st_mode & 0o7777 != self.mode
        if self.chmod:
            os.fchmod(fd, self.mode)
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]


def write_nc1(parts, folder, *, order: str = "roof", grade: str | None = None) -> dict:
    """One NC1 file per beam plate and per hub tube in ``folder``.  ``grade``: default the parts'
    ``steel_grade``.  Returns facts: ``folder, files, tubes, bytes, seconds``.

    A new (or empty) ``folder`` is written whole beside it and put in place when every file is
    complete (a failed or interrupted run leaves no ``nc1/``, and each file is one create instead of
    a create and a rename); into a folder that holds files, each file is written atomically and
    nothing else in it is touched."""
    from .schedules import beam_angles

    t0 = time.perf_counter()
    grade = grade or getattr(parts.spec, "steel_grade", "S355")
    folder = Path(folder)
    files, tubes, size = 0, 0, 0

    def texts():
        for g in parts.of_kind("beam"):
            texts = nc1_texts(g, order=order, grade=grade, density=parts.spec.density(g.kind), angles=beam_angles(g))
            yield from zip(g.ids, texts, itertools.repeat(False))
        for g in parts.of_kind("node"):
            if g.member == "tube":
                texts = nc1_tube_texts(g, order=order, grade=grade, density=parts.spec.group_density(g))
                yield from zip(g.ids, texts, itertools.repeat(True))

    def write_all(out: _Files) -> None:
        nonlocal files, tubes, size
        for pid, text, tube in texts():
            data = text.replace("\n", "\r\n").encode("ascii")
            out.write(f"{pid}.nc1", data)
            files += 1
            tubes += tube
            size += len(data)

    mode = 0o666 & ~umask()                         # the umask read once: thousands of small files
    try:
        if folder.is_dir() and not folder.is_symlink() and any(os.scandir(folder)):
            write_all(_Files(folder, mode))         # a folder with files: each file atomic, the others kept
        else:                                       # none yet: all in a new folder, put in place when complete
            with atomic_dir(folder) as tmp:
                write_all(_Files(tmp, mode, staged=True))
    except OSError as exc:
        raise write_error(folder, "NC1 files", exc) from exc
    return {"file": folder.name + "/", "files": files, "tubes": tubes, "bytes": size,
            "seconds": time.perf_counter() - t0}
