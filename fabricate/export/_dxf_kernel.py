"""The numba kernels behind :func:`fabricate.export.dxf_text.read_outlines_text` on big files (imported only
when numba is installed, through :func:`optimize.kernels.load`).

- :func:`line_ends`: the positions of every newline of ``buf[:n]`` (NumPy: one comparison and one
  ``flatnonzero`` per chunk, then a join);
- :func:`group_codes`: the group code of every code line ``buf[cs:ce]``, as
  :func:`fabricate.export.dxf_text._codes`' fast path reads it: one to eight characters, spaces and
  then at least one digit.  The first line that is not so is returned instead (the caller then reads
  every line the slow way, as before).
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
