"""What the format readers share: the parsed result, tokens with line numbers, number parsing.

Every reader turns a file into a :class:`Parsed` (arrays plus where each
vertex and face came from); :mod:`optimize.io.api` checks it and builds the
:class:`~optimize.mesh.Mesh`.  Messages read ``path:line: what was found,
what was expected`` (``path: byte N: ...`` in binary files).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import MeshError


@dataclass
class Parsed:
    """A mesh as read from a file, before validation.

    V : (n, 3) float
        Vertex positions.
    flat : (c,) int
        Face vertex indices, 0-based, all faces concatenated (not yet checked).
    sizes : (m,) int
        Number of indices of each face.
    vertex_loc, face_loc : (n,), (m,) int
        Line (text) or byte offset (binary) where each vertex / face starts.
    loc_kind : str
        ``"line"`` or ``"byte"``.
    index_base : int
        How the file numbers vertices (1 for OBJ, 0 otherwise), for messages.
    notes : list of str
        Things the reader skipped that a user may want to know.
    """

    V: np.ndarray
    flat: np.ndarray
    sizes: np.ndarray
    vertex_loc: np.ndarray
    face_loc: np.ndarray
    loc_kind: str = "line"
    index_base: int = 0
    notes: list[str] = field(default_factory=list)


def where(path: str, loc: int | None, kind: str = "line") -> str:
    """``path:line`` or ``path: byte N`` (``path`` alone when ``loc`` is None or the file has no
    positions: ``kind`` ``object``, a .3dm file)."""
    if loc is None or kind == "object":
        return path
    return f"{path}:{loc}" if kind == "line" else f"{path}: byte {loc}"


def fail(path: str, loc: int | None, message: str, kind: str = "line") -> MeshError:
    """A :class:`MeshError` reading ``path:loc: message``."""
    return MeshError(f"{where(path, loc, kind)}: {message}")


def decode(data: bytes) -> str:
    """Text of a mesh file; undecodable bytes become U+FFFD and fail where they are used."""
    return data.decode("utf-8", errors="replace")


def one_line(comments) -> list[str]:
    """Header comments for a writer: line breaks turned into spaces (a comment is one line in every
    format), ASCII."""
    return [" ".join(str(c).split()).encode("ascii", "replace").decode("ascii") for c in comments]


def is_count(token: str) -> bool:
    """True for a non-negative decimal integer written in ASCII digits."""
    return token.isascii() and token.isdigit()


class BadToken(Exception):
    """A record count that is not a non-negative integer, at token ``index``, after
    ``done`` complete records."""

    def __init__(self, index: int, done: int):
        super().__init__(index, done)
        self.index = index
        self.done = done


class Tokens:
    """Whitespace tokens of a text with their line numbers, ``#`` comments removed.

    tokens : list of str
    line : (t,) int, 1-based line of each token
    """

    def __init__(self, text: str, *, first_line: int = 1, comments: bool = True):
        tokens: list[str] = []
        counts: list[int] = []
        for ln in text.split("\n"):  # one pass over lines, the tokenizer itself
            if comments and "#" in ln:
                ln = ln[: ln.index("#")]
            t = ln.split()
            tokens.extend(t)
            counts.append(len(t))
        self.tokens = tokens
        self.first_line = first_line
        counts_arr = np.asarray(counts, dtype=np.int64)
        ends = np.cumsum(counts_arr)
        self.line = np.repeat(np.arange(first_line, first_line + len(counts)), counts_arr)
        self._line_list = self.line.tolist()
        self._after = ends.tolist()  # [line - first_line] -> first token after that line
        self.n_lines = len(counts)

    def __len__(self) -> int:
        return len(self.tokens)

    def line_of(self, i: int) -> int:
        """1-based line of token ``i`` (of the last token when ``i`` is past the end)."""
        if i < len(self.tokens):
            return self._line_list[i]
        return self._line_list[-1] if self.tokens else self.first_line

    def records(self, start: int, n: int, size: int | None) -> tuple[list[int], int, int]:
        """Walk ``n`` records from token ``start``; a record is ``size`` tokens, or (size None)
        a count token followed by that many tokens.  The rest of the line holding a
        record's last token is skipped (colours, normals), so records may wrap lines.

        Returns (starts, end, done): token index of each record start, the token after
        the last record, and how many records were complete (``done < n`` means the
        tokens ran out).  Raises :class:`BadToken` for a count that is not a
        non-negative integer.
        """
        toks, after, line, first = self.tokens, self._after, self._line_list, self.first_line
        nt = len(toks)
        starts: list[int] = []
        p = start
        for _ in range(n):  # sequential by nature: each record's length is in the record
            if p >= nt:
                return starts, p, len(starts)
            if size is None:
                tok = toks[p]
                k = int(tok) if is_count(tok) else -1
                if k < 0:
                    raise BadToken(p, len(starts))
                last = p + k
            else:
                last = p + size - 1
            if last >= nt:
                return starts, nt, len(starts)
            starts.append(p)
            p = after[line[last] - first]
        return starts, p, len(starts)


def to_floats(strings: list[str], locate, what: str) -> np.ndarray:
    """Parse ``strings`` as float64 in one call; on failure name the first bad token.

    locate : function ``i -> (loc, context)`` giving the location and a short
        description of string ``i`` (only called on error).
    """
    try:
        return np.array(strings, dtype=np.float64)
    except ValueError:
        pass
    for i, s in enumerate(strings):  # error path only: find the first bad token
        try:
            float(s)
        except ValueError:
            loc, context = locate(i)
            raise MeshError(f"{loc}: '{show(s)}' is not a number, expected {what}{context}") from None
    raise AssertionError("unreachable")  # pragma: no cover


def to_ints(strings: list[str], locate, what: str) -> np.ndarray:
    """Parse ``strings`` as int64 in one call; on failure name the first bad token."""
    try:
        return np.array(strings, dtype=np.int64)
    except (ValueError, OverflowError):
        pass
    for i, s in enumerate(strings):  # error path only
        try:
            int(s)
        except ValueError:
            loc, context = locate(i)
            raise MeshError(f"{loc}: '{show(s)}' is not an integer, expected {what}{context}") from None
    loc, context = locate(0)
    raise MeshError(f"{loc}: an index does not fit in 64 bits, expected {what}{context}")


def pad(flat: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """(m, k) int64: faces padded with -1 from concatenated indices ``flat (c,)`` and ``sizes (m,)``."""
    m = len(sizes)
    k = int(sizes.max()) if m else 3
    F = np.full((m, max(k, 1)), -1, dtype=np.int64)
    rows = np.repeat(np.arange(m), sizes)
    cols = np.arange(len(flat)) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    F[rows, cols] = flat
    return F


def face_lists(mesh, base: int) -> list[list[int]]:
    """Faces of ``mesh`` as lists of ``base``-based indices, in mesh order (for writers)."""
    if not (mesh.F < 0).any():
        return (mesh.F + base).tolist()
    return [[i + base for i in row if i >= 0] for row in mesh.F.tolist()]


def show(s: str, n: int = 40) -> str:
    """``s`` for a message: shortened to ``n`` characters, unprintable ones escaped."""
    s = s if len(s) <= n else s[: n - 3] + "..."
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in s)
