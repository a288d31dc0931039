"""Object File Format (OFF, Geomview), read token by token.

Read: an optional header keyword (``OFF``, ``COFF``, ``NOFF``, ``CNOFF``,
``STOFF``, ... ), the counts ``nv nf [ne]`` on the header line or after it,
``nv`` vertex records and ``nf`` face records ``k i1 .. ik [colour]``, ``#``
comments.  Data after the last declared face is refused (a count too small
would silently drop faces).  A record may wrap across lines: a record is the tokens it needs,
and whatever follows its last token on the same line (colours, normals,
texture coordinates) is skipped.  Binary OFF and 4D/nD variants are refused.

Write: ``OFF``, counts, ``%.17g`` vertices, one face per line.
"""
from __future__ import annotations

import re

import numpy as np

from .common import (
    BadToken,
    Parsed,
    Tokens,
    face_lists,
    fail,
    one_line,
    show,
    to_floats,
    to_ints,
    where,
)

_HEADER = re.compile(r"^(ST)?(C)?(N)?(4)?(n)?OFF$")


def parse_off(text: str, path: str) -> Parsed:
    """Parse OFF ``text`` (read from ``path``, used in messages) into a :class:`Parsed`."""
    tk = Tokens(text)
    toks = tk.tokens
    if not toks:
        raise fail(path, 1, "no data (only comments or blank lines), expected 'OFF' and counts")
    p = _header(tk, path)
    starts, p, done = tk.records(p, 1, 2)
    if not done:
        raise fail(path, tk.line_of(p), "file ends before the counts, expected 'nv nf ne'")
    count_line = tk.line_of(starts[0])
    counts = to_ints(toks[starts[0]: starts[0] + 2],
                     lambda i: (where(path, count_line), ""), "vertex and face counts 'nv nf ne'")
    nv, nf = (int(c) for c in counts)
    if nv < 0 or nf < 0:
        raise fail(path, count_line, f"counts {nv} {nf}, expected non-negative 'nv nf ne'")
    declared = f"{nv} vertices and {nf} faces as declared on line {count_line}"

    vstart, p, done = tk.records(p, nv, 3)
    if done < nv:
        raise fail(path, tk.line_of(len(toks)), f"file ends after {done} of {nv} vertices, "
                                                f"expected {declared}")
    vstart = np.asarray(vstart, dtype=np.int64)
    vidx = (vstart[:, None] + np.arange(3)).ravel().tolist()
    V = to_floats([toks[i] for i in vidx],
                  lambda i: (where(path, tk.line_of(vidx[i])), f" (vertex {i // 3})"),
                  "a vertex coordinate").reshape(-1, 3)

    try:
        fstart, p, done = tk.records(p, nf, None)
    except BadToken as bad:
        raise fail(path, tk.line_of(bad.index), f"'{toks[bad.index]}' starts face {bad.done}, "
                                                "expected its vertex count (an integer >= 0)") from None
    if done < nf:
        raise fail(path, tk.line_of(len(toks)), f"file ends after {done} of {nf} faces, "
                                                f"expected {declared}")
    if p < len(toks):
        raise fail(path, tk.line_of(p), f"'{show(toks[p])}' after the last face, expected the end of "
                                        f"the file ({declared}: is a count too small?)")
    fstart = np.asarray(fstart, dtype=np.int64)
    sizes = np.asarray([int(toks[i]) for i in fstart.tolist()], dtype=np.int64)
    first = np.repeat(fstart + 1, sizes)
    fidx = (first + np.arange(len(first)) - np.repeat(np.cumsum(sizes) - sizes, sizes)).tolist()
    flat = to_ints([toks[i] for i in fidx],
                   lambda i: (where(path, tk.line_of(fidx[i])), ""), "a vertex index")
    return Parsed(V, flat, sizes, tk.line[vstart], tk.line[fstart], "line", 0)


def _header(tk: Tokens, path: str) -> int:
    """Check the header keyword; return the index of the first count token."""
    first = tk.tokens[0]
    if first.lstrip("+-").isdigit():
        return 0  # the keyword is optional
    m = _HEADER.match(first)
    if not m:
        raise fail(path, tk.line_of(0), f"found '{show(first)}', expected an OFF header "
                                        "(OFF, COFF, NOFF, CNOFF, STOFF) or the counts 'nv nf ne'")
    if m.group(4) or m.group(5):
        raise fail(path, tk.line_of(0), f"header '{first}' declares 4D or nD vertices, "
                                        "expected 3D (OFF, COFF, NOFF ...)")
    if len(tk) > 1 and tk.line_of(1) == tk.line_of(0) and tk.tokens[1].upper() == "BINARY":
        raise fail(path, tk.line_of(0), "binary OFF, expected the ASCII form (convert it, "
                                        "e.g. to PLY)")
    return 1


def format_off(mesh, comments=()) -> str:
    """OFF text of ``mesh``: ``%.17g`` vertices, 0-based faces in mesh order; ``comments`` as ``#``
    lines after the keyword."""
    head = "OFF\n" + "".join(f"# {c}\n" for c in one_line(comments))
    head += f"{mesh.n_vertices} {mesh.n_faces} {len(mesh.topology.edges)}\n"
    vs = "".join("%.17g %.17g %.17g\n" % tuple(r) for r in mesh.V.tolist())
    fs = "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in face_lists(mesh, base=0))
    return head + vs + fs
