"""The numba kernels behind :func:`fabricate.export.dxf_text.read_outlines_text` on big files (imported only
when numba is installed, through :func:`optimize.kernels.load`).

- :func:`line_ends`: the positions of every newline of ``buf[:n]`` (NumPy: one comparison and one
  ``flatnonzero`` per chunk, then a join);
- :func:`group_codes`: the group code of every code line ``buf[cs:ce]``, as
  :func:`fabricate.export.dxf_text._codes`' fast path reads it: one to eight characters, spaces and
  then at least one digit.  The first line that is not so is returned instead (the caller then reads
  every line the slow way, as before);
- :func:`intern`: values (entity types, layers, handles) as indices into their distinct values, so that
  Python decodes each distinct one once, and whether all are plain hexadecimal (handles);
- :func:`numbers`: the first value that is not a finite decimal number, as
  :func:`fabricate.export.dxf_text._first_not_number` finds it with a regular expression and NumPy.
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def line_ends(buf, n):
    """``(k,)`` int64: the indices ``i < n`` with ``buf[i] == 10``, in order."""
    k = 0
    for i in range(n):
        if buf[i] == 10:
            k += 1
    out = np.empty(k, np.int64)
    j = 0
    for i in range(n):
        if buf[i] == 10:
            out[j] = i
            j += 1
    return out


@njit(cache=True)
def group_codes(buf, cs, ce):
    """``(codes (n,) int64, first line not read or -1)``: each line ``buf[cs[r]:ce[r]]`` of 1..8 bytes,
    leading spaces then digits only, read as a decimal number."""
    out = np.empty(len(cs), np.int64)
    for r in range(len(cs)):
        a, b = cs[r], ce[r]
        if b - a < 1 or b - a > 8:
            return out, r
        v = 0
        digits = False
        for p in range(a, b):
            ch = buf[p]
            if 48 <= ch <= 57:
                v = v * 10 + (ch - 48)
                digits = True
            elif ch != 32 or digits:
                return out, r
        if not digits:
            return out, r
        out[r] = v
    return out, -1


@njit(cache=True)
def _space(ch) -> bool:
    return ch == 32 or 9 <= ch <= 13          # what bytes.strip() strips: space, \t \n \v \f \r


@njit(cache=True)
def intern(buf, vs, ve, rows):
    """The values ``buf[vs[r]:ve[r]]`` of ``rows``, stripped as ``bytes.strip`` strips, as indices into their
    distinct values: ``(ids (n,), first (k,), last (k,), exact, hexadecimal)``: value ``j`` is
    ``buf[first[j]:last[j]]``; ``exact`` False when two distinct values met in the hash table (the caller then
    reads them in Python); ``hexadecimal``: every value is one or more hexadecimal digits."""
    n = len(rows)
    ids = np.empty(n, np.int64)
    first = np.empty(n, np.int64)
    last = np.empty(n, np.int64)
    table = dict()
    table[np.uint64(0)] = np.int64(-1)        # typed uint64 -> int64; 0 is no key of ours (h | 1 below)
    k = 0
    hexadecimal = True
    for t in range(n):
        a, b = vs[rows[t]], ve[rows[t]]
        while a < b and _space(buf[a]):
            a += 1
        while b > a and _space(buf[b - 1]):
            b -= 1
        h = np.uint64(14695981039346656037)
        for p in range(a, b):
            ch = buf[p]
            h = (h ^ np.uint64(ch)) * np.uint64(1099511628211)
            if not (48 <= ch <= 57 or 65 <= ch <= 70 or 97 <= ch <= 102):
                hexadecimal = False
        if a == b:
            hexadecimal = False
        h = h | np.uint64(1)                   # never 0
        if h not in table:
            table[h] = k
            first[k], last[k] = a, b
            ids[t] = k
            k += 1
            continue
        j = table[h]
        if last[j] - first[j] != b - a:
            return ids, first[:0], last[:0], False, hexadecimal
        for p in range(b - a):
            if buf[first[j] + p] != buf[a + p]:
                return ids, first[:0], last[:0], False, hexadecimal
        ids[t] = j
    return ids, first[:k], last[:k], True, hexadecimal


@njit(cache=True)
def _blank(ch) -> bool:
    return ch == 32 or ch == 9 or ch == 11 or ch == 12      # space \t \v \f (no \n, \r in a value)


@njit(cache=True)
def numbers(buf, vs, ve, rows):
    """``(first, near)``: ``first`` the first ``t`` (or -1) whose value ``buf[vs[r]:ve[r]]``, ``r = rows[t]``,
    is not a decimal number (blanks, a sign, digits with at most one point, at least one digit, an exponent
    ``e``/``E`` with a sign and digits; :data:`fabricate.export.dxf_text.NUMBER`) or is one at least
    ``1e309`` in size (not finite as a double); ``near`` the ``t`` before ``first`` of a size from ``1e308``
    to ``1e309``, which only an exact reading tells finite or not (the caller's ``float``)."""
    near = np.empty(len(rows), np.int64)
    m = 0
    for t in range(len(rows)):
        a, b = vs[rows[t]], ve[rows[t]]
        while a < b and _blank(buf[a]):
            a += 1
        while b > a and _blank(buf[b - 1]):
            b -= 1
        p = a
        if p < b and (buf[p] == 43 or buf[p] == 45):
            p += 1
        digits = 0
        lead = 0                      # the first nonzero digit's place: 10 ** (lead - 1) for 1..., 0: none yet
        seen = False
        while p < b and 48 <= buf[p] <= 57:
            if seen:
                lead += 1
            elif buf[p] != 48:
                seen, lead = True, 1
            digits += 1
            p += 1
        if p < b and buf[p] == 46:
            p += 1
            zeros = 0
            while p < b and 48 <= buf[p] <= 57:
                if not seen:
                    if buf[p] == 48:
                        zeros += 1
                    else:
                        seen, lead = True, -zeros
                digits += 1
                p += 1
        if digits == 0:
            return t, near[:m]
        exp = 0
        if p < b and (buf[p] == 101 or buf[p] == 69):
            p += 1
            sign = 1
            if p < b and (buf[p] == 43 or buf[p] == 45):
                sign = -1 if buf[p] == 45 else 1
                p += 1
            e_digits = 0
            while p < b and 48 <= buf[p] <= 57:
                if exp < 100000000:
                    exp = exp * 10 + (buf[p] - 48)
                e_digits += 1
                p += 1
            if e_digits == 0:
                return t, near[:m]
            exp *= sign
        if p != b:
            return t, near[:m]
        if seen:
            size = lead - 1 + exp         # the value is in [10 ** size, 10 ** (size + 1))
            if size >= 309:
                return t, near[:m]
            if size == 308:
                near[m] = t
                m += 1
    return -1, near[:m]
