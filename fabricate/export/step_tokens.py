"""The records of a STEP DATA section (ISO 10303-21) found and checked with numpy, for the text reader.

:func:`records` finds every record of the DATA section at once over the
file's bytes ``buf (N,) uint8``: strings (quote pairs; ``''`` inside a string
reads as two strings back to back, so the pairs still bound every string),
record ends (``;`` outside strings), ``#`` references outside strings with
their decimal values, each record's id and entity name.  Nothing is built
per record in Python except for the few records with long names
(products, representations).

The grammar of an entity's arguments is then checked position by position
(:meth:`Records.template`): a template such as ``",#,#,?)"`` (``#`` a
reference, ``?`` a ``.T.``/``.F.`` flag, other characters literal) must
cover the record from its first string to its ``;`` exactly, for every
record of the kind, with one gather per template character.  Lists of
references and lists of reals have their own exact checks.

A file with whitespace between tokens (other than a newline after each
``;``) or comments is first rewritten without them (one regular
expression pass: slower, same result).
"""
from __future__ import annotations

import re

import numpy as np
from numpy.lib.stride_tricks import as_strided

from optimize.errors import ExportError
from optimize.warnfilter import filtered

QUOTE, SEMI, HASH, EQ, LPAR, RPAR, COMMA, NL = 39, 59, 35, 61, 40, 41, 44, 10
PAD = 32                       # bytes after the data, so that windows never run off the end
CHUNK = 1 << 22                # bytes scanned at a time (temporaries stay small and in cache)
MAX_DIGITS = 11                # a reference of more digits is refused (ids up to 10^11)
NAME_WINDOW = 24               # entity names shorter than this are classified with numpy
MAX_NAME = 200                 # a longer entity name is refused
LONG_NAME = 48                 # names shorter than this are classified with numpy too, in a second pass
MAX_REAL = 96                  # bytes of one list of reals (three coordinates) at most
REAL_ROWS = 1 << 13            # records whose reals are read at once (about 800 kB of text)
NUMBER_CHARS = np.zeros(256, dtype=bool)
NUMBER_CHARS[np.frombuffer(b"0123456789.+-Ee ", np.uint8)] = True


def _window(buf: np.ndarray, width: int) -> np.ndarray:
    """``(N - width, width)`` view: row ``i`` is ``buf[i:i + width]`` (no copy)."""
    return as_strided(buf, shape=(len(buf) - width, width), strides=(1, 1), writeable=False)


def _scan(buf: np.ndarray, a: int, b: int, chars: tuple[int, ...]) -> list[np.ndarray]:
    """Positions ``(k,)`` of each byte of ``chars`` in ``buf[a:b]``, a chunk at a time (counted
    first, then written into their arrays: no per-chunk pieces to join)."""
    counts = np.zeros((len(chars), -(-(b - a) // CHUNK)), np.int64)
    for i, c in enumerate(range(a, b, CHUNK)):
        part = buf[c:min(c + CHUNK, b)]
        for k, ch in enumerate(chars):
            counts[k, i] = np.count_nonzero(part == ch)
    kind = np.int32 if len(buf) < 2 ** 31 else np.int64            # positions: half the memory
    out = [np.empty(int(n), kind) for n in counts.sum(axis=1)]
    at = np.zeros(len(chars), np.int64)
    for i, c in enumerate(range(a, b, CHUNK)):
        part = buf[c:min(c + CHUNK, b)]
        for k, ch in enumerate(chars):
            n = int(counts[k, i])
            out[k][at[k]:at[k] + n] = np.flatnonzero(part == ch)
            out[k][at[k]:at[k] + n] += c
            at[k] += n
    return out


def compact(body: bytes) -> bytes:
    """The DATA section without whitespace or comments outside strings (a file written with
    whitespace between tokens, records over several lines, or comments)."""
    def keep(m):
        s = m.group()
        return s if s[:1] == b"'" else b""
    return re.sub(rb"'(?:[^']|'')*'|/\*.*?\*/|\s+", keep, body, flags=re.DOTALL)


_ONES, _HIGH = np.uint64(0x0101010101010101), np.uint64(0x8080808080808080)


_BYTE_INDEX = np.uint64(0x0706050403020100)   # byte k holds k


def _lowest_byte(m: np.ndarray) -> np.ndarray:
    """Index 0..7 of the lowest byte of ``m (h,) uint64`` whose high bit is set (only high bits
    set); 8 when none.  The lowest set bit is ``2^(8i + 7)``; ``2^(8i)`` times :data:`_BYTE_INDEX`
    shifts it up by i bytes, so the top byte holds ``7 - i``."""
    low = m & (~m + np.uint64(1))
    top = ((low >> np.uint64(7)) * _BYTE_INDEX) >> np.uint64(56)
    return np.where(m == 0, 8, 7 - top.astype(np.int64))


def _first_byte(x: np.ndarray, byte: int) -> np.ndarray:
    """Index of the first ``byte`` in each little-endian word ``x (h,) uint64`` (8: none)."""
    v = x ^ (_ONES * np.uint64(byte))
    return _lowest_byte((v - _ONES) & ~v & _HIGH)                    # exact for the first zero byte


_MASKS = np.array([(1 << (8 * k)) - 1 for k in range(8)] + [(1 << 64) - 1], dtype=np.uint64)
_C30, _C46 = _ONES * np.uint64(0x30), _ONES * np.uint64(0x46)


def _digits(x: np.ndarray) -> np.ndarray:
    """Number of leading ASCII digits (0..8) in each word ``x (h,) uint64`` (first byte lowest).

    A byte is not a digit when ``b + 0x46``, ``b - 0x30`` or ``b`` has its high bit set;
    carries only reach later bytes, after the first non-digit."""
    return _lowest_byte(((x + _C46) | (x - _C30) | x) & _HIGH)


def _eight_digits(x: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Values of the ``n (h,)`` leading digits (1..8) of each word ``x``, eight at a time (SWAR):
    shifted up by ``8 - n`` bytes the digits after them fall off and zeros lead."""
    v = (x - _C30) << (np.uint64(8) * (np.uint64(8) - np.clip(n, 1, 8).astype(np.uint64)))
    v = (v * np.uint64(10) + (v >> np.uint64(8))) & np.uint64(0x00FF00FF00FF00FF)
    v = (v * np.uint64(100) + (v >> np.uint64(16))) & np.uint64(0x0000FFFF0000FFFF)
    v = (v * np.uint64(10000) + (v >> np.uint64(32))) & np.uint64(0xFFFFFFFF)
    return v.astype(np.int64)


def _word(b: bytes) -> np.uint64:
    return np.uint64(int.from_bytes(b, "little"))


def _ops(pattern: str) -> list[tuple[str, object]]:
    """A template as operations: ``("#", None)``, ``("?", b".T.<literals>")`` (a flag and up to five
    literals after it), ``("N", literals after it)``, ``("lit", up to 8 bytes)``."""
    out: list[tuple[str, object]] = []
    i = 0
    while i < len(pattern):
        ch = pattern[i]
        if ch == "#":
            out.append(("#", None))
            i += 1
        elif ch == "N":
            out.append(("N", len(pattern) - i - 1))
            i += 1
        else:
            j = i + 1 if ch == "?" else i
            while j < len(pattern) and pattern[j] not in "#?N" and j - i < (5 if ch == "?" else 8):
                j += 1
            lit = pattern[i + 1 if ch == "?" else i:j].encode()
            out.append(("?", b".T." + lit) if ch == "?" else ("lit", lit))
            i = j
    return out


class Records:
    """Every record of a DATA section.

    ``buf (N + PAD,) uint8`` the section; per record ``(n,)``: ``start`` (its ``#``),
    ``end`` (its ``;``), ``ids``, ``name_at`` (first character of the entity name),
    ``paren`` (its ``(``; for a complex record the ``(`` after ``=``), ``code`` (index
    into ``names``, ``-1`` complex).  References outside strings ``(h,)``: ``hpos``, ``hval``,
    ``hlen`` (digits).  Strings: ``qpos`` (quotes, in pairs).
    """

    def __init__(self, data: bytes, a: int, b: int, path):
        """The records of ``data[a:b]``, the DATA section (from its first ``#`` to its last ``;``), with
        no whitespace outside strings except one newline after each ``;`` (:func:`compact` makes it
        so).  Positions are indices into ``data`` (not copied unless fewer than ``PAD`` bytes follow)."""
        self.path = path
        if len(data) - b < PAD:
            data = data + b" " * PAD
        self.data = data
        buf = self.buf = np.frombuffer(data, np.uint8)
        self.u64 = np.ndarray(shape=(len(buf) - 8,), dtype="<u8", buffer=data, strides=(1,))  # unaligned
        self.a = a
        q, semi, hpos = _scan(buf, a, b, (QUOTE, SEMI, HASH))
        self.qpos = q
        if len(q) % 2:
            raise ExportError(f"{path}: a string of the DATA section has no closing quote")
        opens, closes = q[0::2], q[1::2]
        full = closes - opens > 1
        if full.any():                                  # ';' and '#' inside strings are text
            o, ln = opens[full] + 1, closes[full] - opens[full] - 1
            inside = np.repeat(o - np.concatenate([[0], np.cumsum(ln)[:-1]]), ln) + np.arange(int(ln.sum()))
            chars = buf[inside]
            if (chars == SEMI).any():
                semi = semi[~np.isin(semi, inside[chars == SEMI])]
            if (chars == HASH).any():
                hpos = hpos[~np.isin(hpos, inside[chars == HASH])]
        if not len(semi) or semi[-1] != b - 1:
            raise ExportError(f"{path}: the DATA section does not end with ';' before ENDSEC;")
        self.end = semi
        start = np.concatenate([[a], semi[:-1] + 1])
        start += buf[start] == NL
        self.start = start
        self._references(hpos)
        self._names()

    # -- references and ids ---------------------------------------------------------------
    def _references(self, hpos: np.ndarray) -> None:
        """Values of every ``#`` reference (eight digits at once, SWAR), record ids, and each
        record's references: ``hpos[ref_lo[i]:ref_hi[i]]``."""
        buf = self.buf
        x = self.u64[hpos + 1]                                        # (h,) the 8 bytes after each '#'
        hlen = _digits(x)
        val = _eight_digits(x, hlen)
        long = np.flatnonzero(hlen == 8)
        nxt = buf[hpos[long] + 9]
        long = long[(nxt >= 48) & (nxt <= 57)]                      # more than eight digits: the next eight
        if long.size:
            x2 = self.u64[hpos[long] + 9]
            n2 = _digits(x2)
            v2 = _eight_digits(x2, n2)
            val[long] = np.where(n2 > 0, val[long] * 10 ** n2 + v2, val[long])
            hlen[long] += n2
        bad = (hlen == 0) | (hlen > MAX_DIGITS)
        if bad.any():
            at = int(hpos[np.argmax(bad)])
            what = "more than 11 digits" if hlen[np.argmax(bad)] else "no digits"
            raise ExportError(f"{self.path}: a '#' reference with {what} in "
                              f"{self.snippet(at)!r}; expected #<digits>")
        self.hpos, self.hval, self.hlen = hpos, val, hlen
        prev = buf[np.maximum(hpos - 1, 0)]
        rec = np.flatnonzero((prev == NL) | (prev == SEMI) | (hpos == self.a))  # a record's own '#'
        if len(rec) != len(self.start) or not np.array_equal(hpos[rec], self.start):
            bad = np.ones(len(self.start), bool)
            if len(rec) == len(self.start):
                bad = hpos[rec] != self.start
            i = int(np.argmax(bad))
            raise ExportError(f"{self.path}: record {i + 1} of the DATA section starts "
                              f"{self.snippet(int(self.start[i]))!r}; expected #<id>=")
        eq = hpos[rec] + 1 + hlen[rec]
        if (buf[eq] != EQ).any():
            i = int(np.argmax(buf[eq] != EQ))
            raise ExportError(f"{self.path}: record {self.snippet(int(self.start[i]))!r}: expected '=' after the id")
        self.ids = val[rec]
        self.ref_lo = rec + 1
        self.ref_hi = np.concatenate([rec[1:], [len(hpos)]])
        self.name_at = eq + 1

    def snippet(self, at: int, n: int = 60) -> str:
        return self.data[at:at + n].split(b";")[0].decode("ascii", "replace")

    # -- entity names -----------------------------------------------------------------------
    def _names(self) -> None:
        n = len(self.start)
        words = [self.u64[self.name_at + 8 * j] for j in range(3)]   # the 24 bytes of each name
        par = np.full(n, NAME_WINDOW, np.int64)
        for j in range(2, -1, -1):                                    # the first '(' of the 24 bytes
            at = _first_byte(words[j], LPAR)
            par = np.where(at < 8, 8 * j + at, par)
        short = (par < NAME_WINDOW) & (par > 0)
        key = [w & _MASKS[np.clip(par - 8 * j, 0, 8)] for j, w in enumerate(words)]  # the name's bytes
        h = key[0] ^ (key[1] * np.uint64(0x9E3779B97F4A7C15)) ^ (key[2] * np.uint64(0xC2B2AE3D27D4EB4F))
        code = np.full(n, -2, dtype=np.int64)
        self.names: list[bytes] = []
        index: dict[bytes, int] = {}
        s = np.flatnonzero(short)
        bucket = (h[s] % np.uint64(65521)).astype(np.int64)
        table = np.full(65521, -1, np.int64)
        table[bucket] = s                                              # one record of each bucket
        rep = table[bucket]
        distinct = table[np.flatnonzero(np.bincount(bucket, minlength=65521))]
        same = (key[0][rep] == key[0][s]) & (key[1][rep] == key[1][s]) & (key[2][rep] == key[2][s])
        if not same.all():                                             # two names in a bucket: exact way
            _, first, inv = np.unique(np.stack([k[s] for k in key], axis=1), axis=0, return_index=True,
                                      return_inverse=True)
            rep, distinct = s[first][inv.ravel()], s[first]
        lookup = np.full(n, -2, np.int64)
        for i in np.sort(distinct).tolist():
            name = self.data[int(self.name_at[i]):int(self.name_at[i] + par[i])]
            lookup[i] = index[name] = len(self.names)
            self.names.append(name)
        code[s] = lookup[rep]
        paren = self.name_at + par
        self._long_names(np.flatnonzero(~short), code, paren, index)
        for i in np.flatnonzero(code == -2).tolist():              # longer names, complex records
            at = int(self.name_at[i])
            if self.data[at] == LPAR:
                code[i], paren[i] = -1, at
                continue
            p = self.data.find(b"(", at, at + MAX_NAME)
            if p < 0:
                raise ExportError(f"{self.path}: record {self.snippet(int(self.start[i]))!r}: no '(' within "
                                  f"{MAX_NAME} characters of the entity name")
            name = self.data[at:p]
            if name not in index:
                index[name] = len(self.names)
                self.names.append(name)
            code[i], paren[i] = index[name], p
        self.code, self.paren, self.index = code, paren, index

    def _long_names(self, rows: np.ndarray, code: np.ndarray, paren: np.ndarray, index: dict) -> None:
        """Names of :data:`NAME_WINDOW` to :data:`LONG_NAME` bytes (product structure entities: a few per
        part) found at once: the bytes before the first '(' of each record's window, one Python step per
        distinct name.  Complex records (``#1=(A()B())``) and longer names are left at ``-2``."""
        rows = rows[self.name_at[rows] < len(self.buf) - LONG_NAME]            # the window inside the file
        if not len(rows):
            return
        W = np.array(_window(self.buf, LONG_NAME)[self.name_at[rows]])       # (r, LONG_NAME) a copy
        rows, W = rows[W[:, 0] != LPAR], W[W[:, 0] != LPAR]
        is_par = W == LPAR
        found = is_par.any(axis=1)
        rows, W, at = rows[found], W[found], np.argmax(is_par[found], axis=1)
        if not len(rows):
            return
        W[np.arange(LONG_NAME)[None, :] >= at[:, None]] = 0                     # the name's bytes only
        words = W.view(np.uint64)                                               # (r, LONG_NAME / 8)
        mix = np.uint64(0x9E3779B97F4A7C15) ** np.arange(1, words.shape[1] + 1, dtype=np.uint64)
        h = np.bitwise_xor.reduce(words * mix[None, :], axis=1)
        _, first, inv = np.unique(h, return_index=True, return_inverse=True)
        inv = inv.ravel()
        if not (words == words[first][inv]).all():                              # two names, one hash
            _, first, inv = np.unique(words, axis=0, return_index=True, return_inverse=True)
            inv = inv.ravel()
        codes = []
        for i in first.tolist():
            name = bytes(W[i, :at[i]])
            if name not in index:
                index[name] = len(self.names)
                self.names.append(name)
            codes.append(index[name])
        code[rows] = np.asarray(codes, np.int64)[inv]
        paren[rows] = self.name_at[rows] + at

    def complex_text(self) -> list[bytes]:
        return [self.data[int(self.start[i]):int(self.end[i])] for i in np.flatnonzero(self.code == -1).tolist()]

    def of(self, name: bytes) -> np.ndarray:
        """Records ``(r,)`` of entity ``name``, in file order."""
        c = self.index.get(name)
        return np.zeros(0, np.int64) if c is None else np.flatnonzero(self.code == c)

    def texts(self, rows: np.ndarray) -> bytes:
        """The records ``rows`` as text, one per line (for the few records read with regular expressions)."""
        d, s, e = self.data, self.start[rows].tolist(), self.end[rows].tolist()
        return b"".join([d[a:b + 1] + b"\n" for a, b in zip(s, e)])

    # -- arguments ------------------------------------------------------------------------------
    def after_string(self, rows: np.ndarray, what: str) -> np.ndarray:
        """Position ``(r,)`` of the closing quote of each record's first argument, a string."""
        buf, q = self.buf, self.qpos
        open_ = self.paren[rows] + 1
        close = open_ + 1
        empty = (buf[open_] == QUOTE) & (buf[close] == QUOTE) & (buf[close + 1] != QUOTE)  # ''
        other = np.flatnonzero(~empty)
        if other.size:
            o = open_[other]
            j = np.minimum(np.searchsorted(q, o), max(len(q) - 2, 0))
            ok = (buf[o] == QUOTE) & (q[j] == o) if len(q) else np.zeros(len(o), bool)
            self._fail(rows[other], ok, what, "its first argument is not a string")
            c = q[j + 1]
            more = buf[c + 1] == QUOTE                             # '' inside the string: it goes on
            while more.any():
                j = np.where(more, j + 2, j)
                c = q[j + 1]
                more = buf[c + 1] == QUOTE
            close[other] = c
        return close

    def template(self, rows: np.ndarray, close: np.ndarray, pattern: str, what: str, per: int = 1):
        """Check that each record continues after its string with ``pattern`` to its ``;``.

        ``#``: a reference, ``?``: ``.T.`` or ``.F.``, ``N``: ``per`` reals separated by commas (only
        once, followed by literals to the end); other characters literal.  Returns ``(refs
        ``[(r,) int] * n#``, flags ``[(r,) bool] * n?``, reals ``(r, per) float`` or None)``.
        """
        lo = self.ref_lo[rows]
        n_ref = pattern.count("#")
        count = self.ref_hi[rows] - lo
        self._fail(rows, count == n_ref, what, f"it has {{}} references; expected {n_ref} ({pattern!r} after "
                   "the name string)", count)
        pos = close + 1
        ok = np.ones(len(rows), bool)
        refs, flags, k, real = [], [], 0, None
        for op, arg in _ops(pattern):
            if op == "#":
                j = lo + k
                ok &= self.hpos[j] == pos
                refs.append(self.hval[j])
                pos = pos + 1 + self.hlen[j]
                k += 1
            elif op == "?":                                      # .T. or .F., then literals
                w = self.u64[pos] & _MASKS[len(arg)]
                t = w == _word(b".T." + arg[3:])
                ok &= t | (w == _word(b".F." + arg[3:]))
                flags.append(t)
                pos = pos + len(arg)
            elif op == "N":
                real = pos
                pos = self.end[rows] - arg
            else:                                                # up to 8 literal bytes at once
                ok &= (self.u64[pos] & _MASKS[len(arg)]) == _word(arg)
                pos = pos + len(arg)
        ok &= pos == self.end[rows]
        self._fail(rows, ok, what, f"its arguments are not ('<string>'{pattern}")
        if real is not None:
            real = self.reals(rows, real, self.end[rows] - (len(pattern) - pattern.index("N") - 1), per, what)
        return refs, flags, real

    def ref_list(self, rows: np.ndarray, close: np.ndarray, what: str, tail: bytes = b")"):
        """``(flat refs, offsets (r + 1,))`` of records ``'<string>',(#a,#b,...)`` + ``tail`` + ``;``."""
        buf, hp, hl = self.buf, self.hpos, self.hlen
        lo = self.ref_lo[rows]
        count = self.ref_hi[rows] - lo
        ok = (buf[close + 1] == COMMA) & (buf[close + 2] == LPAR) & (count > 0)
        self._fail(rows, ok, what, "expected a list of references (#a,#b,...) after the name string")
        j = np.repeat(lo - np.concatenate([[0], np.cumsum(count)[:-1]]), count) + np.arange(int(count.sum()))
        first = np.zeros(len(j), bool)
        off = np.concatenate([[0], np.cumsum(count)])
        first[off[:-1]] = True
        after = hp[j] + 1 + hl[j]                                  # the separator after each reference
        prev_after = np.concatenate([[0], after[:-1]])
        good = np.where(first, hp[j] == np.repeat(close + 3, count), (hp[j] == prev_after + 1)
                        & (buf[np.maximum(prev_after, 0)] == COMMA))
        last_after = after[off[1:] - 1]
        good_rec = np.logical_and.reduceat(good, off[:-1]) if len(j) else np.ones(len(rows), bool)
        good_rec &= buf[last_after] == RPAR
        for t, ch in enumerate(tail):
            good_rec &= buf[last_after + 1 + t] == ch
        good_rec &= last_after + 1 + len(tail) == self.end[rows]
        self._fail(rows, good_rec, what, f"its arguments are not ('<string>',(#a,#b,...){tail.decode()}")
        return self.hval[j], off

    def reals(self, rows: np.ndarray, a: np.ndarray, b: np.ndarray, per: int, what: str) -> np.ndarray:
        """``(r, per)`` reals written in ``buf[a:b]`` of each record, separated by commas (read
        :data:`REAL_ROWS` records at a time: the temporaries stay in cache)."""
        n = len(rows)
        length = b - a
        width = int(length.max()) if n else 1
        if width > MAX_REAL or (length < 1).any():
            i = int(np.argmax((length > MAX_REAL) | (length < 1)))
            self._fail(rows, np.arange(n) != i, what, f"expected {per} numbers in at most {MAX_REAL} characters")
        out = np.empty((n, per))
        for c in range(0, n, REAL_ROWS):
            s = slice(c, c + REAL_ROWS)
            out[s] = self._reals(rows[s], a[s], length[s], width, per, what)
        return out

    def _reals(self, rows, a, length, width: int, per: int, what: str) -> np.ndarray:
        buf = self.buf
        fits = a + width + 1 <= len(buf)
        if fits.all():
            W = np.array(_window(buf, width + 1)[a])                      # (r, width + 1) copy
        else:            # records near the end of the data: their rows from a space-padded tail
            at = int(a[~fits].min())
            tail = np.concatenate([buf[at:], np.full(width + 1, 32, np.uint8)])
            W = np.empty((len(a), width + 1), np.uint8)
            W[fits] = _window(buf, width + 1)[a[fits]]
            W[~fits] = _window(tail, width + 1)[a[~fits] - at]
        W[np.arange(width + 1)[None, :] >= length[:, None]] = 32          # a space ends every row
        commas = W == COMMA
        self._fail(rows, commas.sum(axis=1) == per - 1, what, f"expected {per} numbers separated by commas")
        W[commas] = 32
        self._fail(rows, NUMBER_CHARS[W].all(axis=1), what, "a character that is not part of a number")
        with filtered("ignore", DeprecationWarning):
            try:
                x = np.fromstring(W.tobytes(), dtype=np.float64, sep=" ")
            except ValueError:
                x = np.zeros(0)
        if x.size != len(rows) * per or not np.isfinite(x).all():
            raise ExportError(f"{self.path}: a {what} has a coordinate that is not a finite number")
        return x.reshape(len(rows), per)

    def _fail(self, rows, ok, what, why, values=None) -> None:
        if len(ok) and not ok.all():
            i = int(np.argmax(~ok))
            if values is not None:
                why = why.format(int(values[i]))
            raise ExportError(f"{self.path}: {what} #{int(self.ids[rows[i]])} "
                              f"({self.snippet(int(self.start[rows[i]]), 80)!r}): {why}")
