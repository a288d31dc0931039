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
from optimize.errors import write_error

NUM = "{:10.3f}"
TEXT_MAX = 60
"""The longest text a header line holds here.  A longer value is never cut silently: it is abbreviated by
:func:`fit` to its first ``TEXT_MAX - 9`` characters, ``~`` and the 8 hex digits of its CRC-32 (the
same value always gives the same text, two values that differ give different texts), and written
whole in the file's ``**`` comment line."""


def fit(value: str) -> str:
    """``value`` as a header text of at most :data:`TEXT_MAX` ASCII characters (see there); a character
    outside printable ASCII becomes ``_``."""
    import zlib

    text = "".join(c if 32 <= ord(c) < 127 else "_" for c in str(value))
    if len(text) <= TEXT_MAX:
        return text
    return f"{text[:TEXT_MAX - 9]}~{zlib.crc32(text.encode('ascii')):08x}"


def _along_axis(group) -> np.ndarray | None:
    """(p,) angle (rad) of the beam axis in each solid's flat frame, or None for a group without a
    placement (then x runs along the longer side of the outline's rectangle)."""
    T = getattr(group, "transform", None)
    if T is None or getattr(group, "centre_line", None) is None:
        return None
    from .schedules import beam_axes

    t = np.einsum("pji,pj->pi", np.asarray(T, dtype=float)[:, :3, :3], beam_axes(group))   # in the part frame
    return np.arctan2(t[:, 1], t[:, 0])


def _frame(F: np.ndarray, angle: np.ndarray | None) -> np.ndarray:
    """(p, k, 2) the outlines ``F (p, k, 2)`` turned so that x runs along the beam axis (``angle``, from
    :func:`_along_axis`) or along the longer side, moved to the positive quadrant."""
    if angle is None:
        turn = np.ptp(F[:, :, 1], axis=1) > np.ptp(F[:, :, 0], axis=1)
        F = np.where(turn[:, None, None], np.stack([F[:, :, 1], -F[:, :, 0]], axis=2), F)
    else:
        c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
        F = np.stack([c * F[:, :, 0] + s * F[:, :, 1], -s * F[:, :, 0] + c * F[:, :, 1]], axis=2)
    return F - F.min(axis=1, keepdims=True)


def contour(group, i: int) -> np.ndarray:
    """(k, 2) the flat outline of part ``i``, x along its beam's axis (a group without placements: along
    the longer side), lower-left corner at the origin."""
    angle = _along_axis(group)
    return _frame(np.asarray(group.flat[i], dtype=float)[None], None if angle is None else angle[i:i + 1])[0]


def _signed_max(pair) -> float:
    """The value of larger magnitude of a pair (an end's bevel on its two sides), with its sign."""
    pair = np.asarray(pair, dtype=float)
    return float(pair[np.argmax(np.abs(pair))])


def _bevels(group, i: int, k: int) -> np.ndarray:
    """(k, 2) the weld preparation of each outline edge of part ``i`` (degrees from square on the ``v``
    face's side and on the back's: ``bevel_deg``), zeros for a group without them; NaN read as 0."""
    B = getattr(group, "bevel_deg", None)
    if B is None or np.shape(B)[1] != k:
        return np.zeros((k, 2))
    return np.nan_to_num(np.asarray(B[i], dtype=float))


def _texts(group, i: int, order: str, kind: str, where: str) -> list[str]:
    """The four text lines: the order, what the part is, the mesh element, its assembly."""
    from fabricate.cad.parts import unit_id

    return [fit(order), fit(getattr(group, "member", "") or kind), fit(f"mesh {where} {int(group.element[i])}"),
            fit(f"assembly {unit_id(group.ids[i])}")]


def nc1_text(group, i: int, *, order: str, grade: str, density: float, angles: dict) -> str:
    """The NC1 file of plate ``i`` of ``group`` (a beam group); ``angles``: the group's
    :func:`fabricate.export.schedules.beam_angles` (the steel cut list's end cuts)."""
    from fabricate.cad.parts import unit_id

    Q = contour(group, i)
    length, height = float(Q[:, 0].max()), float(Q[:, 1].max())
    t = float(group.thickness_mm[i])
    weight = float(group.volume_mm3[i]) * density * 1e-9
    perimeter = float(np.linalg.norm(np.roll(Q, -1, axis=0) - Q, axis=1).sum())
    paint = (2.0 * float(group.area_mm2[i]) + perimeter * t) * 1e-6 / (length * 1e-3)
    web = angles["mitre"][i]
    bevel = (_signed_max(angles["end_bevel"][i, 0]), _signed_max(angles["end_bevel"][i, 1]))
    pid = group.ids[i]
    head = [fit(order), fit(unit_id(pid)), "1", fit(pid), fit(grade), "1", f"PL{t:g}", "B"]
    numbers = [length, height, 0.0, 0.0, t, 0.0, weight / (length * 1e-3), paint, web[0], web[1],
               bevel[0], bevel[1]]
    texts = _texts(group, i, order, group.kind, "edge")
    lines = ["ST", f"** {pid}.nc1 written by conical-fab for {_comment(order)}"]
    lines += [f"  {v}" for v in head] + ["  " + NUM.format(v).strip() for v in numbers] + [f"  {v}" for v in texts]
    lines.append("AK")
    closed = np.vstack([Q, Q[:1]])
    prep = np.vstack([_bevels(group, i, len(Q)), np.zeros((1, 2))])
    for j, ((x, y), (b1, b2)) in enumerate(zip(closed.tolist(), prep.tolist())):
        lines.append(("  v " if j == 0 else "    ") + f"{NUM.format(x)} {NUM.format(y)} {NUM.format(0.0)}"
                     f" {NUM.format(b1)} {NUM.format(0.0)} {NUM.format(b2)} {NUM.format(0.0)}")
    cx, cy = Q.mean(axis=0)
    lines += ["SI", f"  v {NUM.format(cx)} {NUM.format(cy)} {NUM.format(0.0)} 10 {pid}", "EN", ""]
    return "\n".join(lines)


def tube_diameter(group) -> np.ndarray:
    """(p,) mm: the outside diameter of each hub tube (its ``K``-gon's circumscribed circle, the CHS the
    cut list orders), to 0.1 mm."""
    V = np.asarray(group.vertices, dtype=float)
    ring = V[:, :V.shape[1] // 4]
    return np.round(2.0 * np.linalg.norm(ring - ring.mean(axis=1, keepdims=True), axis=2).mean(axis=1), 1)


def nc1_tube_text(group, i: int, *, order: str, grade: str, density: float) -> str:
    """The NC1 file of hub tube ``i`` of ``group`` (a node group of member ``tube``, vertices outer lower
    ring ``0..K-1`` first: :func:`fabricate.cad.hubs.tube_faces`)."""
    from fabricate.cad.parts import unit_id

    diameter = float(tube_diameter(group)[i])
    wall = float(group.thickness_mm[i])
    length = float(group.length_mm[i])
    weight = float(group.volume_mm3[i]) * density * 1e-9
    pid = group.ids[i]
    head = [fit(order), fit(unit_id(pid)), "1", fit(pid), fit(grade), "1", f"RO{diameter:g}x{wall:g}", "RO"]
    numbers = [length, diameter, 0.0, wall, wall, 0.0, weight / (length * 1e-3), np.pi * diameter * 1e-3,
               0.0, 0.0, 0.0, 0.0]
    texts = _texts(group, i, order, "hub tube", "vertex")
    texts[1] = "hub tube"
    lines = ["ST", f"** {pid}.nc1 written by conical-fab for {_comment(order)}"]
    lines += [f"  {v}" for v in head] + ["  " + NUM.format(v).strip() for v in numbers] + [f"  {v}" for v in texts]
    lines += ["SI", f"  v {NUM.format(0.5 * length)} {NUM.format(0.5 * diameter)} {NUM.format(0.0)} 10 {pid}",
              "EN", ""]
    return "\n".join(lines)


def _comment(order: str) -> str:
    return "".join(c if 32 <= ord(c) < 127 else "_" for c in str(order))


def _bevel_max(pair: np.ndarray) -> np.ndarray:
    """(p,) :func:`_signed_max` of every row of ``pair (p, 2)``: the first on a tie, a NaN as argmax finds it."""
    a, b = pair[:, 0], pair[:, 1]
    second = (np.abs(b) > np.abs(a)) | (np.isnan(b) & ~np.isnan(a))
    return np.where(second, b, a)


def _template(k: int | None) -> str:
    """The ``%`` template of one file (LF line ends): a plate with a contour of ``k`` corners
    (``k + 1`` lines, closed, each with the weld preparation of the edge it starts), or a tube (``k``
    None: no contour)."""
    st = ["ST", "** %s.nc1 written by conical-fab for %s", "  %s", "  %s", "  1", "  %s", "  %s", "  1"]
    if k is None:
        st += ["  RO%gx%g", "  RO"] + ["  %.3f"] * 12 + ["  %s"] * 4
    else:
        st += ["  PL%g", "  B"] + ["  %.3f"] * 12 + ["  %s"] * 4 + ["AK"]
        prep = " %10.3f      0.000 %10.3f      0.000"
        st += ["  v %10.3f %10.3f      0.000" + prep] + ["    %10.3f %10.3f      0.000" + prep] * k
    return "\n".join(st + ["SI", "  v %10.3f %10.3f      0.000 10 %s", "EN", ""])


def nc1_texts(group, *, order: str, grade: str, density: float, angles: dict) -> list[str]:
    """:func:`nc1_text` of every plate of ``group`` (the same text): the numbers of the whole group at
    once, ``flat (p, k, 2)`` turned and moved as :func:`contour` does each part."""
    F = np.asarray(group.flat, dtype=float)                                  # (p, k, 2)
    Q = _frame(F, _along_axis(group))
    p, k = Q.shape[:2]
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
    B = getattr(group, "bevel_deg", None)
    prep = np.nan_to_num(np.asarray(B, dtype=float)) if B is not None and np.shape(B)[1] == k else np.zeros((p, k, 2))
    rows = np.concatenate([Q, prep], axis=2)                                 # (p, k, 4): x y angle1 angle2
    closed = np.concatenate([rows, np.concatenate([Q[:, :1], np.zeros((p, 1, 2))], axis=2)], axis=1)
    closed = closed.reshape(p, -1).tolist()
    centre = Q.mean(axis=1).tolist()
    template, kind = _template(k), group.kind
    return [template % (pid, _comment(order), *head, th, *num, *_texts(group, i, order, kind, "edge"), *xy, *c, pid)
            for i, (pid, th, num, xy, c) in enumerate(zip(group.ids, t.tolist(), numbers, closed, centre))
            for head in [_head(order, pid, grade)]]


def _head(order: str, pid: str, grade: str) -> tuple[str, str, str, str]:
    """The header's texts before the profile: order, drawing (the assembly), piece (the part), grade."""
    from fabricate.cad.parts import unit_id

    return fit(order), fit(unit_id(pid)), fit(pid), fit(grade)


def nc1_tube_texts(group, *, order: str, grade: str, density: float) -> list[str]:
    """:func:`nc1_tube_text` of every tube of ``group`` (the same text), the numbers of the group at once."""
    diameter = tube_diameter(group)
    wall = np.asarray(group.thickness_mm, dtype=float)
    length = np.asarray(group.length_mm, dtype=float)
    weight = np.asarray(group.volume_mm3, dtype=float) * density * 1e-9
    zero = np.zeros(len(wall))
    numbers = np.stack([length, diameter, zero, wall, wall, zero, weight / (length * 1e-3), np.pi * diameter * 1e-3,
                        zero, zero, zero, zero], axis=1).tolist()
    mark = np.stack([0.5 * length, 0.5 * diameter], axis=1).tolist()
    template, order_text = _template(None), fit(order)
    return [template % (pid, _comment(order), *_head(order, pid, grade), d, w, *num,
                        order_text, "hub tube", *_texts(group, i, order, "hub tube", "vertex")[2:], *m, pid)
            for i, (pid, d, w, num, m) in enumerate(zip(group.ids, diameter.tolist(), wall.tolist(), numbers, mark))]


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
    grade = grade or getattr(parts.spec, "steel_grade", "S355J2")
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
