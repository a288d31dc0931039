"""STL (binary and ASCII), read only: the triangle soup a modeller exports, welded into a mesh.

STL stores every triangle with its own three corners and no connectivity.
Corners with bit-identical coordinates are welded into one vertex (a
modeller writes a shared corner the same way every time); triangles that
welding leaves with a repeated vertex, or with collinear corners (area at most
:data:`optimize.mesh.core.ZERO_AREA` of the longest edge squared, as CAD exporters
write to close T-junctions), are dropped, with a note.  Binary files are recognised by their size (``84 + 50 n`` bytes for
``n`` triangles, whatever the header says: some exporters start a binary
header with ``solid``); anything else must be ASCII (``solid ... facet normal
... outer loop vertex x y z ... endloop endfacet ... endsolid``).
"""
from __future__ import annotations

import numpy as np

from ..core import ZERO_AREA, area_ratio
from .common import BOM, Parsed, Tokens, fail, show, to_floats, where

_RECORD = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])


def parse_stl(data: bytes, path: str) -> Parsed:
    """``Parsed`` of an STL file's bytes: welded vertices, triangles, their lines / byte offsets."""
    if len(data) >= 84:
        n = int(np.frombuffer(data, "<u4", 1, 80)[0])
        if 84 + 50 * n == len(data):
            return _binary(data, n, path)
    if data.startswith(BOM):
        data = data[len(BOM):]
    if not data.lstrip()[:5].lower() == b"solid":
        raise fail(path, None, f"{len(data)} bytes: neither a binary STL (84 + 50 n bytes) nor an "
                               "ASCII STL (starting 'solid')")
    return _ascii(data.decode("ascii", errors="replace"), path)


def _binary(data: bytes, n: int, path: str) -> Parsed:
    rec = np.frombuffer(data, _RECORD, n, 84)
    corners = rec["v"].reshape(-1, 3).astype(np.float64)
    loc = 84 + 50 * np.arange(n)
    return _weld(corners, loc, "byte", path)


#: One ASCII facet: 21 tokens, keywords where given, numbers (None) elsewhere.
_FACET = ("facet", "normal", None, None, None, "outer", "loop", "vertex", None, None, None,
          "vertex", None, None, None, "vertex", None, None, None, "endloop", "endfacet")
_KEYWORDS = np.array([j for j, w in enumerate(_FACET) if w])
_CORNERS = np.array([8, 9, 10, 12, 13, 14, 16, 17, 18])
_GRAMMAR = "'facet normal nx ny nz', 'outer loop', three 'vertex x y z', 'endloop', 'endfacet'"


def _ascii(text: str, path: str) -> Parsed:
    """Facets read by their grammar, 21 tokens each; 'solid' and 'endsolid' lines (whose names may
    be any words, 'loop' or 'vertex' too) are skipped, so several solids in one file are read."""
    tk = Tokens(text, comments=False)
    toks = tk.tokens
    line = tk.line
    first = np.flatnonzero(np.r_[True, line[1:] != line[:-1]]) if len(toks) else np.zeros(0, int)
    names = [i for i in first.tolist() if toks[i].lower() in ("solid", "endsolid")]
    keep = np.ones(len(toks), dtype=bool)
    keep[np.isin(line, line[names])] = False
    idx = np.flatnonzero(keep)
    if not len(idx):
        raise fail(path, 1, f"ASCII STL without any 'vertex' line (no facet), expected facets of {_GRAMMAR}")
    n = -(-len(idx) // 21)  # facets, the last one perhaps cut short
    cols = np.tile(np.arange(21), n)[: len(idx)]
    kw = np.isin(cols, _KEYWORDS)
    found = [toks[i].lower() for i in idx[kw].tolist()]
    want = [_FACET[j] for j in cols[kw].tolist()]
    bad = next((k for k, (a, b) in enumerate(zip(found, want)) if a != b), None)
    if bad is not None:
        pos = int(np.flatnonzero(kw)[bad])
        f, j, tok = pos // 21, int(cols[pos]), toks[idx[pos]]
        at = int(line[idx[pos]])
        if _FACET[j] == "endloop" and found[bad] == "vertex":
            raise fail(path, at, f"facet {f} has more than 3 vertices, expected 3 (STL facets are triangles)")
        if _FACET[j] == "vertex" and found[bad] == "endloop":
            raise fail(path, at, f"facet {f} has {(j - 7) // 4} vertices, expected 3 (STL facets are "
                                 "triangles)")
        raise fail(path, at, f"found '{show(tok)}' in facet {f}, expected '{_FACET[j]}' (a facet is "
                             f"{_GRAMMAR})")
    if len(idx) % 21:
        raise fail(path, int(line[idx[-1]]), f"file ends inside facet {n - 1}, expected {_GRAMMAR}")
    corner = idx.reshape(-1, 21)[:, _CORNERS].ravel().tolist()
    corners = to_floats([toks[i] for i in corner],
                        lambda i: (where(path, int(line[corner[i]])), f" (facet {i // 9})"),
                        "a vertex coordinate 'vertex x y z'").reshape(-1, 3)
    return _weld(corners, line[idx[0::21]], "line", path)


def _weld(corners: np.ndarray, loc: np.ndarray, kind: str, path: str) -> Parsed:
    """Weld bit-identical corners ``(3t, 3)``; drop triangles left degenerate.  ``loc (t,)``."""
    V, inv = np.unique(corners, axis=0, return_inverse=True)
    T = inv.reshape(-1, 3)
    degenerate = (T[:, 0] == T[:, 1]) | (T[:, 1] == T[:, 2]) | (T[:, 0] == T[:, 2])
    degenerate[~degenerate] = area_ratio(V, T[~degenerate]) <= ZERO_AREA  # collinear corners
    notes = [f"{path}: {len(corners)} triangle corners welded into {len(V)} vertices (bit-identical "
             "coordinates)"]
    if degenerate.any():
        first = int(np.argmax(degenerate))
        notes.append(f"{path}: {int(degenerate.sum())} degenerate triangle(s) dropped (a repeated corner or "
                     "zero area; the "
                     f"first at {'line' if kind == 'line' else 'byte'} {int(loc[first])})")
    keep = ~degenerate
    T, loc = T[keep], np.asarray(loc)[keep]
    used = np.unique(T)
    remap = np.full(len(V), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    first_seen = np.full(len(V), -1, dtype=np.int64)
    first_seen[T[::-1].ravel()] = np.repeat(loc[::-1], 3)  # the earliest triangle using each vertex
    return Parsed(V=V[used], flat=remap[T].ravel(), sizes=np.full(len(T), 3), vertex_loc=first_seen[used],
                  face_loc=loc, loc_kind=kind, notes=notes)
