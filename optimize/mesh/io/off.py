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
    is_count,
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
        raise _faces_run_out(tk, path, fstart, p, nf, declared)
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


def _faces_run_out(tk: Tokens, path: str, fstart: list[int], p: int, nf: int, declared: str):
    """The error when the tokens run out before ``nf`` face records (``fstart``: the complete
    ones; ``p``: where the incomplete one starts, or the end).  A record with too few indices
    takes the next record's count as its last index and the file ends early, far from the
    mistake: so name the first record that wraps onto a line that holds a face record of its own
    (a record legitimately wrapped over lines continues with indices only); else the record
    the file ends inside; else the last line."""
    toks, done = tk.tokens, len(fstart)
    ends = f"the file ends after {done} of {nf} faces ({declared})"
    if done:
        s = np.asarray(fstart, dtype=np.int64)
        k = np.asarray([int(toks[i]) for i in fstart], dtype=np.int64)
        start_line, last_line = tk.line[s], tk.line[s + k]
        for f in np.nonzero(last_line > start_line)[0].tolist():  # error path only
            nxt = tk.after_line(int(start_line[f]))  # the first token of the next line that has any
            line2 = tk.line_of(nxt)
            n2 = tk.tokens_on_line(line2)
            if is_count(toks[nxt]) and n2 >= 1 + int(toks[nxt]):
                own = nxt - int(s[f]) - 1
                return fail(path, int(start_line[f]),
                            f"face {f} ('{show(' '.join(toks[s[f]: nxt]))}') has {own} of its {k[f]} indices on "
                            f"its line and takes the rest from line {line2} "
                            f"('{show(' '.join(toks[nxt: nxt + n2]))}', which reads as a face of its own); "
                            f"then {ends}: expected {k[f]} indices after the count {k[f]}")
    if p < len(toks):  # the file ends inside a record
        k, rec = int(toks[p]), show(" ".join(toks[p: p + 12]))
        return fail(path, tk.line_of(p), f"face {done} ('{rec}') has {len(toks) - p - 1} of its {k} indices "
                                         f"when {ends}: expected {k} indices after the count")
    return fail(path, tk.line_of(len(toks)), f"file ends after {done} of {nf} faces, expected {declared}")


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
