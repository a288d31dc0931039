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
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from optimize.atomic import umask
from optimize.errors import ExportError

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


def _write_atomic(target: Path, data: bytes, mode: int) -> None:
    """``data`` to a temporary file beside ``target``, then renamed to it (removed on failure)."""
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part", dir=target.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            os.fchmod(fh.fileno(), mode)
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def write_nc1(parts, folder, *, order: str = "roof", grade: str | None = None) -> dict:
    """One NC1 file per beam plate and per hub tube in ``folder`` (created; each file atomic).  ``grade``:
    default the parts' ``steel_grade``.  Returns facts: ``folder, files, tubes, bytes, seconds``."""
    from .schedules import beam_angles

    t0 = time.perf_counter()
    grade = grade or getattr(parts.spec, "steel_grade", "S355")
    folder = Path(folder)
    files, tubes, size = 0, 0, 0

    def texts():
        for g in parts.of_kind("beam"):
            density = parts.spec.density(g.kind)
            angles = beam_angles(g)
            for i, pid in enumerate(g.ids):
                yield pid, nc1_text(g, i, order=order, grade=grade, density=density, angles=angles), False
        for g in parts.of_kind("node"):
            if g.member != "tube":
                continue
            density = parts.spec.group_density(g)
            for i, pid in enumerate(g.ids):
                yield pid, nc1_tube_text(g, i, order=order, grade=grade, density=density), True

    try:
        folder.mkdir(parents=True, exist_ok=True)
        mode = 0o666 & ~umask()                 # read once: thousands of small files
        for pid, text, tube in texts():
            data = text.replace("\n", "\r\n").encode("ascii")
            _write_atomic(folder / f"{pid}.nc1", data, mode)
            files += 1
            tubes += tube
            size += len(data)
    except OSError as exc:
        raise ExportError(f"{folder}: cannot write the NC1 files ({exc.strerror or exc})") from None
    return {"file": folder.name + "/", "files": files, "tubes": tubes, "bytes": size,
            "seconds": time.perf_counter() - t0}
