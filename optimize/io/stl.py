"""STL (binary and ASCII), read only: the triangle soup a modeller exports, welded into a mesh.

STL stores every triangle with its own three corners and no connectivity.
Corners with bit-identical coordinates are welded into one vertex (a
modeller writes a shared corner the same way every time); triangles that
welding leaves with a repeated vertex (zero-area slivers) are dropped, with
a note.  Binary files are recognised by their size (``84 + 50 n`` bytes for
``n`` triangles, whatever the header says: some exporters start a binary
header with ``solid``); anything else must be ASCII (``solid ... facet normal
... outer loop vertex x y z ... endloop endfacet ... endsolid``).
"""
from __future__ import annotations

import numpy as np

from .common import Parsed, Tokens, fail

_RECORD = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])


def parse_stl(data: bytes, path: str) -> Parsed:
    """``Parsed`` of an STL file's bytes: welded vertices, triangles, their lines / byte offsets."""
    if len(data) >= 84:
        n = int(np.frombuffer(data, "<u4", 1, 80)[0])
        if 84 + 50 * n == len(data):
            return _binary(data, n, path)
    if not data.lstrip()[:5].lower() == b"solid":
        raise fail(path, None, f"{len(data)} bytes: neither a binary STL (84 + 50 n bytes) nor an "
                               "ASCII STL (starting 'solid')")
    return _ascii(data.decode("ascii", errors="replace"), path)


def _binary(data: bytes, n: int, path: str) -> Parsed:
    rec = np.frombuffer(data, _RECORD, n, 84)
    corners = rec["v"].reshape(-1, 3).astype(np.float64)
    loc = 84 + 50 * np.arange(n)
    return _weld(corners, loc, "byte", path)


def _ascii(text: str, path: str) -> Parsed:
    tk = Tokens(text, comments=False)
    words = np.char.lower(np.asarray(tk.tokens, dtype=str))
    at = np.nonzero(words == "vertex")[0]
    loops = np.nonzero(words == "loop")[0]  # "outer loop": one per facet
    if not len(at):
        raise fail(path, 1, "ASCII STL without any 'vertex' line, expected facets of three vertices")
    # every facet must have exactly three vertices: count the vertices after each 'loop'
    owner = np.searchsorted(loops, at) - 1
    if len(loops) and (owner < 0).any():
        raise fail(path, int(tk.line[at[np.argmax(owner < 0)]]), "'vertex' before any 'outer loop'")
    per = np.bincount(owner, minlength=len(loops)) if len(loops) else np.array([len(at)])
    bad = np.nonzero(per != 3)[0]
    if len(bad):
        k = int(bad[0])
        line = int(tk.line[loops[k]]) if len(loops) else 1
        raise fail(path, line, f"facet {k} has {int(per[k])} vertices, expected 3 (STL facets are triangles)")
    idx = at[:, None] + np.arange(1, 4)
    if idx.max() >= len(words):
        raise fail(path, int(tk.line[at[-1]]), "the last 'vertex' has fewer than 3 coordinates")
    raw = np.asarray(tk.tokens, dtype=object)[idx]
    try:
        corners = np.array(raw.tolist(), dtype=np.float64)
    except ValueError:
        for i, row in enumerate(raw.tolist()):  # find the culprit for the message
            for tok in row:
                try:
                    float(tok)
                except ValueError:
                    raise fail(path, int(tk.line[at[i]]), f"vertex coordinate {tok!r} is not a number, "
                                                          "expected 'vertex x y z'") from None
        raise
    return _weld(corners, tk.line[at[0::3]], "line", path)


def _weld(corners: np.ndarray, loc: np.ndarray, kind: str, path: str) -> Parsed:
    """Weld bit-identical corners ``(3t, 3)``; drop triangles left degenerate.  ``loc (t,)``."""
    V, inv = np.unique(corners, axis=0, return_inverse=True)
    T = inv.reshape(-1, 3)
    degenerate = (T[:, 0] == T[:, 1]) | (T[:, 1] == T[:, 2]) | (T[:, 0] == T[:, 2])
    notes = [f"{path}: {len(corners)} triangle corners welded into {len(V)} vertices (bit-identical "
             "coordinates)"]
    if degenerate.any():
        first = int(np.argmax(degenerate))
        notes.append(f"{path}: {int(degenerate.sum())} degenerate triangle(s) dropped (a repeated corner; the "
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
