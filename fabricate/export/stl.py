"""Binary STL of every part (one triangle soup, float32, mm), validated with manifold3d.

The 80-byte header records the local origin: ``conical-fab mm origin=x,y,z parts=N``;
add the origin to every coordinate to get model coordinates.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from optimize.atomic import atomic_open
from optimize.errors import ExportError, writing

from .meshes import group_triangles, validate_manifold

RECORD = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])


def header_text(origin: np.ndarray, n_parts: int) -> bytes:
    """The 80-byte STL header naming the origin offset (mm)."""
    text = "conical-fab mm origin={:.17g},{:.17g},{:.17g} parts={}".format(*origin, n_parts).encode("ascii")
    if len(text) > 80:
        text = "conical-fab mm origin={:.9g},{:.9g},{:.9g} parts={}".format(*origin, n_parts).encode("ascii")
    return text.ljust(80, b" ")[:80]


def parse_header(header: bytes) -> dict:
    """``{"origin": (3,) float, "parts": int}`` from a header written by :func:`header_text`."""
    text = header.decode("ascii", errors="replace")
    out = {"origin": np.zeros(3), "parts": None}
    for token in text.split():
        if token.startswith("origin="):
            out["origin"] = np.array([float(x) for x in token[7:].split(",")])
        elif token.startswith("parts="):
            out["parts"] = int(token[6:])
    return out


def unit_normals(X: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit normals ``(n_x, n_y, n_z)``, each ``(p, t)`` float64, of the triangles ``T (t, 3)`` of the
    solids ``X (p, nv, 3)``: ``cross(b - a, c - a) / max(|.|, 1e-300)`` with the operations of
    ``np.cross`` and ``np.linalg.norm`` (the same bits), on one coordinate array at a time."""
    C = np.ascontiguousarray(np.moveaxis(X, 2, 0))                    # (3, p, nv)
    a = C[:, :, T[:, 0]]                                              # (3, p, t)
    u, v = C[:, :, T[:, 1]], C[:, :, T[:, 2]]
    u -= a
    v -= a
    n0, n1, n2 = u[1] * v[2], u[2] * v[0], u[0] * v[1]
    n0 -= u[2] * v[1]
    n1 -= u[0] * v[2]
    n2 -= u[1] * v[0]
    length = n0 * n0
    length += n1 * n1
    length += n2 * n2
    np.sqrt(length, out=length)
    np.maximum(length, 1e-300, out=length)
    n0 /= length
    n1 /= length
    n2 /= length
    return n0, n1, n2


def group_records(group, origin: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``(p, t)`` :data:`RECORD` of the group's triangles (fan triangles), into ``out`` if given:
    vertices relative to ``origin``, float32 of the float64 values, unit normals from the float64
    vertices (:func:`unit_normals`)."""
    X, T = group_triangles(group, origin)
    rec = np.empty((len(X), len(T)), dtype=RECORD) if out is None else out
    rec["attr"] = 0
    rec["v"] = X.astype(np.float32)[:, T]                             # float32 of each vertex: the same values
    normal = rec["normal"]
    for k, n in enumerate(unit_normals(X, T)):
        normal[..., k] = n
    return rec


def records(parts, origin: np.ndarray) -> np.ndarray:
    """``(t,)`` :data:`RECORD`: every triangle of every part, part order (:func:`group_records`)."""
    sizes = [len(g) * sum(len(f) - 2 for f in g.faces) for g in parts.groups]
    rec = np.empty(sum(sizes), dtype=RECORD)
    lo = 0
    for g, size in zip(parts.groups, sizes):
        group_records(g, origin, rec[lo:lo + size].reshape(len(g), -1))
        lo += size
    return rec


def write_stl(parts, path, *, origin: np.ndarray | None = None) -> dict:
    """Write a binary STL (atomic) after checking every part with manifold3d.

    origin : (3,) offset subtracted from every coordinate (default
    ``parts.local_origin()``), recorded in the header.
    Returns facts: ``file, bytes, triangles, origin_mm, manifold (facts), seconds``.
    """
    t0 = time.perf_counter()
    path = Path(path)
    origin = parts.local_origin() if origin is None else np.asarray(origin, dtype=float)
    facts = validate_manifold(parts, origin)
    rec = records(parts, origin)
    with writing(path, "STL file", needed=84 + rec.nbytes), atomic_open(path, "wb") as fh:
        fh.write(header_text(origin, len(parts)))
        fh.write(np.uint32(len(rec)).tobytes())
        fh.write(rec.view(np.uint8))  # a file write (ndarray.tofile's short write has no errno)
    return {"file": path.name, "bytes": path.stat().st_size, "triangles": len(rec), "parts": len(parts),
            "origin_mm": origin.tolist(), "manifold": facts, "seconds": time.perf_counter() - t0}


def read_stl(path) -> tuple[np.ndarray, dict]:
    """Triangles ``(t, 3, 3) float32`` and the parsed header of a binary STL."""
    path = Path(path)
    data = path.read_bytes()
    if len(data) < 84:
        raise ExportError(f"{path}: {len(data)} bytes, too short for a binary STL")
    count = int(np.frombuffer(data, "<u4", 1, 80)[0])
    if len(data) != 84 + 50 * count:
        raise ExportError(f"{path}: header says {count} triangles ({84 + 50 * count} bytes), file has "
                          f"{len(data)} bytes; expected a binary STL")
    rec = np.frombuffer(data, RECORD, count, 84)
    return rec["v"].copy(), parse_header(data[:80])


def write_stl_parts(parts, folder, *, origin: np.ndarray | None = None) -> dict:
    """One binary STL per part, ``folder/<id>.stl`` (atomic each), same origin as ``model.stl``.

    Touching parts share corner coordinates, so a program that welds the combined ``model.stl``
    fuses them into fewer pieces; one file per part keeps every solid on its own (for a slicer, a
    viewer that welds, or a CAM set-up per part).  Returns facts: ``folder, files, triangles, seconds``.
    """
    t0 = time.perf_counter()
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    origin = parts.local_origin() if origin is None else np.asarray(origin, dtype=float)
    files = tris = 0
    for g in parts.groups:
        rec = group_records(g, origin)                                # (p, t)
        t = rec.shape[1]
        for i, pid in enumerate(g.ids):  # one file per part
            path = folder / f"{pid}.stl"
            with writing(path, "STL file", needed=84 + rec[i].nbytes), atomic_open(path, "wb") as fh:
                fh.write(header_text(origin, 1))
                fh.write(np.uint32(t).tobytes())
                fh.write(rec[i].view(np.uint8))
            files += 1
            tris += t
    return {"folder": folder.name, "files": files, "triangles": tris, "origin_mm": origin.tolist(),
            "seconds": time.perf_counter() - t0}
