"""``read_mesh`` and ``write_mesh``: the format chosen by ``fmt`` or the file extension.

Reading checks what only the file knows (syntax, counts, numbers) in the
format module and then, here, what every format shares (finite coordinates,
faces of 3+ vertices, indices in range) with the file position of the
culprit; the :class:`~optimize.mesh.core.Mesh` then checks topology and geometry,
and its messages are given the line (or byte) of the face or vertex they name.
"""
from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from ...atomic import atomic_open
from ...errors import MeshError, write_error
from ..core import Mesh
from .common import BOM, Parsed, check_file, decode, pad, read_bytes, where
from .obj import format_obj, parse_obj
from .off import format_off, parse_off
from .ply import ENCODINGS, format_ply, parse_ply
from .stl import parse_stl

#: Formats by name; ``fmt`` arguments and file extensions use these names (STL, 3dm: read only).
FORMATS = ("obj", "off", "ply", "stl", "3dm")


def detect_format(path: str | os.PathLike, fmt: str | None = None) -> str:
    """The format name for ``path``: ``fmt`` when given, else the extension (case-insensitive)."""
    name = fmt if fmt is not None else Path(path).suffix.lstrip(".")
    key = name.lower()
    if key not in FORMATS:
        given = f"format '{fmt}'" if fmt is not None else f"extension '{Path(path).suffix}'"
        raise MeshError(f"{path}: unknown mesh {given}, expected one of "
                        + ", ".join(f".{f}" for f in FORMATS))
    return key


def read_mesh(path: str | os.PathLike, *, fmt: str | None = None, layer: str | None = None,
              name: str | None = None) -> Mesh:
    """Read a polygon mesh from an OBJ, OFF or PLY (ascii or binary) file, a Rhino .3dm file
    (one Mesh object, picked by ``layer`` and / or object ``name`` when there are several, see
    :mod:`optimize.mesh.io.rhino`), or a triangle surface from an STL file (binary or ASCII; corners
    welded, see :mod:`optimize.mesh.io.stl`).

    Returns a validated :class:`Mesh` named ``str(path)`` (with notes on
    anything skipped or repaired).  Raises :class:`MeshError` reading
    ``path:line: what was found, what was expected`` for every malformed input.
    """
    label = str(path)
    kind = detect_format(path, fmt)
    if (layer is not None or name is not None) and kind != "3dm":
        raise MeshError(f"{label}: a layer or object name picks a mesh in a .3dm file, not in a .{kind} file")
    if kind == "3dm":
        from .rhino import parse_3dm

        check_file(path, kind)  # a regular file within the size limit (rhino3dm reads it itself)
        return build_mesh(parse_3dm(label, layer=layer, name=name), label)
    name = label
    data = read_bytes(path, kind)
    if not data.strip() or data.strip() == BOM:
        raise MeshError(f"{name}:1: empty file, expected a {kind.upper()} mesh")
    if kind == "obj":
        parsed = parse_obj(decode(data), name)
    elif kind == "off":
        parsed = parse_off(decode(data), name)
    elif kind == "stl":
        parsed = parse_stl(data, name)
    else:
        parsed = parse_ply(data, name)
    return build_mesh(parsed, name)


def mesh_units(path: str | os.PathLike, *, fmt: str | None = None) -> tuple[str, float | None] | None:
    """The length unit a mesh file states: ``(name, mm per unit)`` for a Rhino .3dm file (its
    ``ModelUnitSystem``; mm per unit None when it has none or a custom one), None for a format that
    states none (OBJ, OFF, PLY, STL: the caller's ``units`` says).  Reading the unit of a .3dm
    reads the file (rhino3dm has no lighter way).  An OBJ states one in the header comment some
    exporters write (Maya: ``# This file uses centimeters as units for non-parametric coordinates.``),
    read from the file's first :data:`OBJ_HEADER_BYTES` only."""
    kind = detect_format(path, fmt)
    if kind == "obj":
        return _obj_units(path)
    if kind != "3dm":
        return None
    from .rhino import model_units

    check_file(path, "3dm")
    return model_units(str(path))


OBJ_HEADER_BYTES = 4096
"""How much of an OBJ file's start is searched for a unit comment."""
OBJ_UNITS = {"millimeters": 1.0, "millimetres": 1.0, "centimeters": 10.0, "centimetres": 10.0, "meters": 1000.0,
             "metres": 1000.0, "inches": 25.4, "feet": 304.8, "kilometers": 1e6, "yards": 914.4}


def _obj_units(path) -> tuple[str, float | None] | None:
    """``(name, mm per unit)`` from an OBJ header comment ``# ... uses <unit> as units ...`` (None: none)."""
    import re
    import stat

    try:  # a file that is missing or not regular (a pipe would block): none stated; the reader says why
        if not stat.S_ISREG(os.stat(path).st_mode):
            return None
        with open(path, "rb") as fh:
            head = fh.read(OBJ_HEADER_BYTES).decode("latin-1")
    except OSError:
        return None
    for line in head.splitlines()[:-1] or head.splitlines():  # the last line may be cut off
        if not line.startswith("#"):
            if line.strip():
                break  # the header ends at the first record
            continue
        m = re.search(r"\buses\s+([A-Za-z]+)\s+as\s+units\b", line)
        if m:
            name = m.group(1).lower()
            return name, OBJ_UNITS.get(name)
    return None


def build_mesh(parsed: Parsed, name: str) -> Mesh:
    """Check ``parsed`` and make the :class:`Mesh`; every error names the file position."""
    V, flat, sizes = parsed.V, parsed.flat, parsed.sizes
    at = lambda loc: where(name, int(loc), parsed.loc_kind)  # noqa: E731
    if len(sizes) == 0:
        raise MeshError(f"{name}: no faces ({len(V)} vertices), expected a polygon mesh")
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        raise MeshError(f"{at(parsed.vertex_loc[i])}: vertex {i} is {V[i].tolist()}, "
                        "expected finite coordinates")
    small = sizes < 3
    if small.any():
        f = int(np.argmax(small))
        raise MeshError(f"{at(parsed.face_loc[f])}: face {f} has {int(sizes[f])} vertex index(es), "
                        "expected at least 3")
    out = (flat < 0) | (flat >= len(V))
    if out.any():
        k = int(np.argmax(out))
        f = int(np.searchsorted(np.cumsum(sizes), k, side="right"))
        b = parsed.index_base
        raise MeshError(f"{at(parsed.face_loc[f])}: face {f} refers to vertex {int(flat[k]) + b}, "
                        f"expected {b}..{len(V) - 1 + b} ({len(V)} vertices)")
    F = pad(flat, sizes, lambda f: at(parsed.face_loc[f]))
    try:
        mesh = Mesh(V, F, name=name)
    except MeshError as exc:
        raise _located(exc, parsed, name) from None
    mesh.notes.extend(parsed.notes)
    return mesh


def _located(exc: MeshError, parsed: Parsed, name: str) -> MeshError:
    """``exc`` from :class:`Mesh` with the file position of the face or vertex it names."""
    msg = str(exc)
    body = msg[len(name) + 2:] if msg.startswith(f"{name}: ") else msg
    m = re.search(r"\bface (\d+)\b", body)
    faces = re.search(r"\bfaces \[([\d, ]+)\]", body)
    vertex = re.search(r"\bvertex (\d+)\b", body)
    loc = None
    if m:
        loc = parsed.face_loc[int(m.group(1))]
    elif faces:
        loc = parsed.face_loc[int(faces.group(1).split(",")[-1])]
    elif vertex:
        loc = parsed.vertex_loc[int(vertex.group(1))]
    if loc is None:
        return MeshError(f"{name}: {body}")
    return MeshError(f"{where(name, int(loc), parsed.loc_kind)}: {body}")


def write_mesh(path: str | os.PathLike, mesh: Mesh, *, fmt: str | None = None,
               binary: bool = True, comments=()) -> None:
    """Write ``mesh`` atomically as OBJ, OFF or PLY (same vertex order and faces).

    Text coordinates use ``%.17g`` and binary PLY stores doubles, so reading
    the file back gives exactly ``mesh.V`` and ``mesh.F``.  ``binary`` selects
    binary little-endian PLY (default) or ascii PLY; it is ignored for OBJ/OFF.
    Raises :class:`MeshError` for an unknown format, :class:`ExportError` if
    the file cannot be written.  ``comments`` (one line each) go into the header: a
    result that missed its tolerance says so in the file itself.
    """
    kind = detect_format(path, fmt)
    if kind == "stl":
        raise MeshError(f"{path}: STL is read here, not written (it keeps no connectivity); "
                        "expected .obj, .off or .ply")
    if kind == "3dm":
        raise MeshError(f"{path}: a mesh alone is not written as .3dm (fabricate run writes model.3dm "
                        "with every part); expected .obj, .off or .ply")
    if kind == "ply":
        payload = format_ply(mesh, ENCODINGS[1] if binary else ENCODINGS[0], comments)
    else:
        text = format_obj(mesh, comments) if kind == "obj" else format_off(mesh, comments)
        payload = text.encode("ascii")  # numbers, and comments made ASCII by one_line
    try:
        with atomic_open(path, "wb") as fh:
            fh.write(payload)
    except OSError as exc:
        raise write_error(path, f".{kind} file", exc, needed=len(payload)) from exc
