"""What the format readers share: the parsed result, tokens with line numbers, number parsing.

Every reader turns a file into a :class:`Parsed` (arrays plus where each
vertex and face came from); :mod:`optimize.mesh.io.api` checks it and builds the
:class:`~optimize.mesh.core.Mesh`.  Messages read ``path:line: what was found,
what was expected`` (``path: byte N: ...`` in binary files).

Bounded time and memory, whatever the bytes: :func:`read_bytes` reads only a
regular file of at most :data:`MAX_FILE_BYTES`; :func:`declared` checks every
count a file declares against the bytes actually present *before* anything is
allocated for it; :func:`pad` refuses a padded face array more than
:data:`optimize.mesh.core.PAD_FACTOR` times the indices in the file (the mesh does the
same for vertex stars); no reader builds fixed-width
string arrays (their size is the longest token times the token count).  So a
reader's memory is proportional to the file's size, and every refusal names
the limit.
"""
from __future__ import annotations

import os
import stat
from dataclasses import dataclass, field

import numpy as np

from ...errors import MeshError
from ..core import PAD_FACTOR, padding_limit


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


#: Largest mesh file read (bytes): the readers need a few times the file size in memory.
MAX_FILE_BYTES = 4 << 30
BOM = b"\xef\xbb\xbf"


def read_bytes(path, kind: str) -> bytes:
    """The bytes of the mesh file ``path`` (format name ``kind`` for messages).

    Refuses, with a :class:`MeshError` naming the path, what :func:`check_file`
    refuses and a file that cannot be read or grows while being read.
    """
    name = str(path)
    st = check_file(path, kind)
    try:
        with open(path, "rb") as fh:
            data = fh.read(st.st_size + 1)  # never more than the size stat reported, plus one
    except OSError as exc:
        raise MeshError(f"{name}: cannot be read ({exc.strerror or exc}), expected a readable "
                        f".{kind} file") from None
    if len(data) > st.st_size:
        raise MeshError(f"{name}: grew while being read (past {st.st_size} bytes), expected a "
                        "finished file")
    return data


def check_file(path, kind: str) -> os.stat_result:
    """``os.stat`` of ``path`` once it is known to be a regular file of at most
    :data:`MAX_FILE_BYTES`; refuses (:class:`MeshError` naming the path) a missing file, a
    folder, anything not a regular file (a device such as ``/dev/zero``, a pipe, a socket:
    they may never end) and a larger file."""
    name = str(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise MeshError(f"{name}: no such file, expected an existing .{kind} mesh file") from None
    except OSError as exc:
        raise MeshError(f"{name}: cannot be read ({exc.strerror or exc}), expected a readable "
                        f".{kind} file") from None
    if stat.S_ISDIR(st.st_mode):
        raise MeshError(f"{name}: is a folder, expected a .{kind} mesh file")
    if not stat.S_ISREG(st.st_mode):
        raise MeshError(f"{name}: is not a regular file (a device, pipe or socket), expected a "
                        f".{kind} mesh file")
    if st.st_size > MAX_FILE_BYTES:
        raise MeshError(f"{name}: {st.st_size} bytes, expected at most {MAX_FILE_BYTES} bytes "
                        "(the reader's limit)")
    return st


def declared(path: str, loc: int | None, what: str, count: int, unit: int, available: int,
             kind: str = "line", where_from: str = "follow") -> None:
    """Check a count a file declares before allocating for it.

    ``count`` records of at least ``unit`` bytes each must fit in the
    ``available`` bytes of the file; otherwise a :class:`MeshError` at ``loc``
    says how many bytes the count implies and how many there are.
    """
    if count < 0:
        raise fail(path, loc, f"{what}: count {count}, expected a count >= 0", kind)
    if unit > 0 and count * unit > available:
        raise fail(path, loc, f"{what}: {count} records of at least {unit} byte(s) need "
                              f"{count * unit} bytes, but only {available} bytes {where_from}; "
                              "expected a count the file holds (is it truncated?)", kind)


def decode(data: bytes) -> str:
    """Text of a mesh file, without a leading UTF-8 byte order mark; undecodable bytes become
    U+FFFD and fail where they are used."""
    if data.startswith(BOM):
        data = data[len(BOM):]
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

    def after_line(self, line: int) -> int:
        """Index of the first token after line ``line`` (1-based)."""
        return self._after[line - self.first_line]

    def tokens_on_line(self, line: int) -> int:
        """How many tokens line ``line`` (1-based) holds."""
        return self.after_line(line) - (self.after_line(line - 1) if line > self.first_line else 0)

    def records(self, start: int, n: int, size: int | None) -> tuple[list[int], int, int]:
        """Walk ``n`` records from token ``start``; a record is ``size`` tokens, or (size None)
        a count token followed by that many tokens.  The rest of the line holding a
        record's last token is skipped (colours, normals), so records may wrap lines.

        Returns (starts, end, done): token index of each record start, the token after
        the last complete record (when the tokens ran out inside a record: where that
        record starts), and how many records were complete (``done < n`` means the
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
                return starts, p, len(starts)
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


def pad(flat: np.ndarray, sizes: np.ndarray, at=None) -> np.ndarray:
    """(m, k) int64: faces padded with -1 from concatenated indices ``flat (c,)`` and ``sizes (m,)``.

    Refuses (:class:`MeshError`) a padded array over :func:`optimize.mesh.core.padding_limit`
    (``PAD_FACTOR * c`` slots, at least ``PAD_FLOOR``): one huge polygon among many small faces.
    ``at``: function ``face -> "path:line"`` for the message.
    """
    m = len(sizes)
    k = int(sizes.max()) if m else 3
    limit = padding_limit(len(flat))
    if m * k > limit:
        f = int(np.argmax(sizes))
        head = at(f) if at is not None else "mesh"
        raise MeshError(f"{head}: face {f} has {k} vertices; the {m} faces padded to that size need "
                        f"{m * k} index slots, over the limit of {limit} ({PAD_FACTOR} x the {len(flat)} "
                        "indices in the file); expected polygons of comparable size (split or "
                        "triangulate the large one)")
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
