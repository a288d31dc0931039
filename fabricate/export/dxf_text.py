"""An independent, fast reader of the flat outlines in an ASCII DXF file (for the full check).

``read_outlines_text(path)`` splits the file into its (group code, value)
pairs at once, finds the ENTITIES section, and reads every ``LWPOLYLINE``
on layer ``CUT`` (vertices from codes 10/20, the part id from its
``CONICAL_FAB`` XDATA, code 1000) and counts the ``TEXT`` ids on ``ETCH``,
with numpy over all pairs instead of building a document.  It lints what a
CAD program needs to open the file: every group code an integer, the file
ends with ``EOF``, sections balanced, entity handles unique hexadecimal, each
outline closed with as many vertices as its count (code 90) says, ``$INSUNITS`` read from the
header.  Every value is read as strictly as ezdxf's loader reads it (:func:`_strict`), in every
section and entity, not only the outlines: a value whose group code makes it a number (a TEXT's
insertion point, any vertex, a count) that is not one, or is not finite, and an x coordinate
without its y, fail the file (:class:`ExportError` naming the file, the line and the value).

It shares no code with the writer (:mod:`fabricate.export.dxf`) nor with
ezdxf; ``fabricate check --occ`` loads and audits the whole file with ezdxf
instead.
"""
from __future__ import annotations

import binascii
import re
from pathlib import Path

import numpy as np

from optimize.errors import ExportError
from optimize.warnfilter import filtered

APPID = "CONICAL_FAB"
NUMBER_CODES = ((10, 79), (90, 99), (110, 149), (160, 179), (210, 239), (270, 299), (370, 389), (400, 409), (420, 429),
                (440, 469), (1010, 1071))
"""Group codes whose values ezdxf's loader reads as numbers (``float``, or ``int(float(v))``): points,
distances, angles, counts, flags, colours (:data:`ezdxf.lldxf.types.TYPE_TABLE`)."""
POINT_CODES = ((10, 18), (110, 112), (210, 213), (1010, 1013))
"""Group codes of an x coordinate, which its y (the code plus 10) must follow."""
BINARY_CODES = ((310, 319), (1004, 1004))
"""Group codes of hexadecimal binary data."""
NUMBER = re.compile(rb"[ \t\v\f]*+[+-]?+(?:[0-9]++(?:\.[0-9]*+)?+|\.[0-9]++)(?:[eE][+-]?+[0-9]++)?+[ \t\v\f]*+")
"""A decimal number as ``float`` reads it, blanks around it allowed (no ``inf``, ``nan``, ``_``); possessive
(nothing is tried twice: six times as fast)."""
_NUMBERS = re.compile(rb"(?:" + NUMBER.pattern + rb"\n)*+")


def _table(ranges) -> np.ndarray:
    out = np.zeros(1072, bool)
    for lo, hi in ranges:
        out[lo:hi + 1] = True
    return out


IS_NUMBER, IS_POINT, IS_BINARY = _table(NUMBER_CODES), _table(POINT_CODES), _table(BINARY_CODES)


CHUNK = 1 << 22
KERNEL_FROM_BYTES = 4 << 20
"""From this file size on the lines are split and the group codes read by the compiled kernels
(:mod:`fabricate.export._dxf_kernel`, when numba is installed): below, loading them costs more than
they save."""


def _kernel(n_bytes: int):
    """The compiled kernels for a file of ``n_bytes``, or None (:func:`optimize.kernels.load`)."""
    from optimize import kernels

    return kernels.load("fabricate.export._dxf_kernel") if n_bytes >= KERNEL_FROM_BYTES else None


def _codes(buf: np.ndarray, data: bytes, cs: np.ndarray, ce: np.ndarray, path, kernel=None) -> np.ndarray:
    """``(n,)`` group codes of the code lines ``data[cs:ce]``: up to 8 characters, spaces then digits,
    read eight bytes at a time (or by ``kernel``, :mod:`fabricate.export._dxf_kernel`); other lines (a
    sign, more characters) by ``np.fromstring``."""
    L = ce - cs
    if kernel is not None:
        codes, bad = kernel.group_codes(buf, cs, ce)
        if bad < 0:
            return codes
    elif len(cs) and (L >= 1).all() and (L <= 8).all():
        words = np.ndarray(shape=(len(buf) - 8,), dtype="<u8", buffer=data, strides=(1,))  # unaligned
        W = words[cs].view(np.uint8).reshape(-1, 8)                          # (n, 8) the line's bytes
        inside = np.arange(8)[None, :] < L[:, None]
        space = W == 32
        digit = (W >= 48) & (W <= 57)
        lead = np.logical_and.accumulate(space, axis=1)                      # spaces before the digits
        ok = np.all(~inside | digit | lead, axis=1) & np.any(inside & digit, axis=1)
        if ok.all():
            x = np.ascontiguousarray(np.where(space, 48, W).astype(np.uint8)).view("<u8")[:, 0]
            k = (np.uint64(8) - L.astype(np.uint64)) * np.uint64(8)
            v = (x - np.uint64(0x3030303030303030)) << k
            v = (v * np.uint64(10) + (v >> np.uint64(8))) & np.uint64(0x00FF00FF00FF00FF)
            v = (v * np.uint64(100) + (v >> np.uint64(16))) & np.uint64(0x0000FFFF0000FFFF)
            v = (v * np.uint64(10000) + (v >> np.uint64(32))) & np.uint64(0xFFFFFFFF)
            return v.astype(np.int64)
    with filtered("ignore", DeprecationWarning):
        try:
            codes = np.fromstring(b" ".join([data[a:b] for a, b in zip(cs.tolist(), ce.tolist())]),
                                  dtype=np.int64, sep=" ")
        except ValueError:
            codes = np.zeros(0, np.int64)
    if codes.size != len(cs):
        raise ExportError(f"{path}: a group code is not an integer; not an ASCII DXF file")
    return codes


def read_outlines_text(path, *, sheets: bool = False) -> tuple[dict[str, np.ndarray], dict]:
    """``({part id: CUT outline (k, 2)}, facts)``; facts: ``lint`` (problems), ``audit_errors``
    (their count), ``units`` ($INSUNITS), ``texts`` (TEXT entities on ETCH); with ``sheets``, also
    ``sheets`` ``(s, 4, 2)`` the corners of the stock sheets' frames (LWPOLYLINE on SHEET) and
    ``sheet_labels`` their labels (TEXT on SHEET)."""
    from .verify import not_regular

    path = Path(path)
    if (what := not_regular(path)) is not None:                  # a pipe or a device may never end
        raise ExportError(f"{path}: {what}, not a DXF file; refused unopened")
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ExportError(f"{path}: cannot read the DXF file ({exc.strerror or exc})") from None
    if b"\r" in data:
        data = data.replace(b"\r", b"")
    n_data = len(data)
    data += b"\n" + b" " * 16                      # the last line ends; words never run off the end
    buf = np.frombuffer(data, np.uint8)
    kernel = _kernel(n_data)
    if kernel is not None:
        ends = kernel.line_ends(buf, n_data + 1)
    else:
        ends = np.concatenate([np.flatnonzero(buf[c:min(c + CHUNK, n_data + 1)] == 10) + c
                               for c in range(0, n_data + 1, CHUNK)])
    starts = np.concatenate([[0], ends[:-1] + 1])
    if len(ends) and starts[-1] == n_data:          # the newline after the last line
        starts, ends = starts[:-1], ends[:-1]
    lint: list[str] = []
    if len(starts) % 2:
        lint.append(f"{len(starts)} lines: a group code without its value")
        starts, ends = starts[:-1], ends[:-1]
    cs, ce, vs, ve = starts[0::2], ends[0::2], starts[1::2], ends[1::2]
    codes = _codes(buf, data, cs, ce, path, kernel)
    _strict(buf, data, codes, vs, ve, path, kernel)

    def pick(idx) -> np.ndarray:
        """The values at ``idx`` (indices or mask), stripped, as an object array of str."""
        idx = np.flatnonzero(idx) if getattr(idx, "dtype", None) is np.dtype(bool) else np.asarray(idx, np.int64)
        if kernel is not None and len(idx):             # each distinct value decoded once
            ids, first, last, exact, _ = kernel.intern(buf, vs, ve, idx)
            if exact:
                distinct = [data[a:b].decode("utf-8", "replace") for a, b in zip(first.tolist(), last.tolist())]
                return np.array(distinct + [None], dtype=object)[:-1][ids]
        return np.array([data[a:b].strip().decode("utf-8", "replace")
                         for a, b in zip(vs[idx].tolist(), ve[idx].tolist())] + [None], dtype=object)[:-1]

    def handle_lint(idx) -> list[str]:
        """The handles at ``idx``: duplicates, and whether each is hexadecimal (``int(h, 16)``)."""
        distinct = None
        if kernel is not None and len(idx):
            _, first, _, exact, plain = kernel.intern(buf, vs, ve, idx)
            if exact and plain:                       # plain digits: int(h, 16) reads every one
                distinct, hexadecimal = len(first), True
        if distinct is None:
            handles = pick(idx).tolist()
            distinct = len(set(handles))
            try:
                [int(h, 16) for h in handles]
                hexadecimal = True
            except ValueError:
                hexadecimal = False
        out = [f"{len(idx) - distinct} duplicate entity handles"] if distinct != len(idx) else []
        return out + ([] if hexadecimal else ["an entity handle is not hexadecimal"])

    def numbers(idx, dtype, what: str) -> np.ndarray:
        idx = np.flatnonzero(idx)
        text = b" ".join([data[a:b] for a, b in zip(vs[idx].tolist(), ve[idx].tolist())])
        with filtered("ignore", DeprecationWarning):
            try:
                x = np.fromstring(text, dtype=np.float64, sep=" ") if idx.size else np.zeros(0)
            except ValueError:
                x = np.zeros(0)
        if x.size != idx.size:
            raise ExportError(f"{path}: {what} is not a number")
        return x.astype(dtype)

    vals_last = data[int(vs[-1]):int(ve[-1])] if len(vs) else b""
    zero = np.nonzero(codes == 0)[0]
    kinds = pick(zero)
    if vals_last.strip() != b"EOF":
        lint.append("the file does not end with 0/EOF")
    if int(np.sum(kinds == "SECTION")) != int(np.sum(kinds == "ENDSEC")):
        lint.append("SECTION and ENDSEC do not pair up")
    units = 0
    nine = np.nonzero(codes == 9)[0]
    hdr = nine[pick(nine) == "$INSUNITS"]
    if hdr.size and hdr[0] + 1 < len(codes) and codes[hdr[0] + 1] == 70:
        units = int(float(data[int(vs[hdr[0] + 1]):int(ve[hdr[0] + 1])]))   # as ezdxf: a finite number
    two = np.nonzero(codes == 2)[0]
    sec = two[pick(two) == "ENTITIES"]
    if not sec.size:
        raise ExportError(f"{path}: no ENTITIES section")
    a = int(sec[0]) + 1
    ends = zero[(zero >= a) & (kinds == "ENDSEC")]
    b = int(ends[0]) if ends.size else len(codes)
    in_sec = (zero >= a) & (zero < b)
    starts = zero[in_sec]                                        # one 0/TYPE per entity
    a = int(starts[0]) if len(starts) else b
    ent = np.searchsorted(starts, np.arange(a, b), side="right") - 1      # >= 0: a is the first start
    c = codes[a:b]
    n = len(starts)
    etype = kinds[in_sec]
    layer = np.full(n, "", dtype=object)
    on = c == 8
    layer[ent[on]] = pick(np.flatnonzero(on) + a)
    lint += handle_lint(np.flatnonzero(c == 5) + a)
    cut = (etype == "LWPOLYLINE") & (layer == "CUT")
    texts = int(np.sum((etype == "TEXT") & (layer == "ETCH")))
    in_cut = cut[ent]
    full = np.zeros(len(codes), bool)

    def at(mask):                                                # a mask over the section -> the file
        full[:] = False
        full[a:b] = mask
        return full

    xs = numbers(at(in_cut & (c == 10)), float, "an outline vertex")
    ys = numbers(at(in_cut & (c == 20)), float, "an outline vertex")
    if xs.size != ys.size or not (np.isfinite(xs).all() and np.isfinite(ys).all()):
        lint.append("outline vertices without both coordinates, or not finite")
        facts = {"lint": lint, "audit_errors": len(lint), "units": units, "texts": texts,
                 "reader": "independent DXF text reader"}
        return {}, (dict(facts, sheets=np.zeros((0, 4, 2)), sheet_labels=[]) if sheets else facts)
    owner = ent[in_cut & (c == 10)]
    cut_ids = np.nonzero(cut)[0]
    count = np.bincount(owner, minlength=n)[cut_ids]
    declared = np.zeros(n, dtype=np.int64)
    decl = in_cut & (c == 90)
    declared[ent[decl]] = numbers(at(decl), np.int64, "a vertex count (90)")
    flags = np.zeros(n, dtype=np.int64)
    fl = in_cut & (c == 70)
    flags[ent[fl]] = numbers(at(fl), np.int64, "a polyline flag (70)")
    if np.any(declared[cut_ids] != count):
        lint.append(f"{int(np.sum(declared[cut_ids] != count))} outlines with a vertex count (90) "
                    "other than their vertices")
    if np.any(flags[cut_ids] & 1 == 0):
        lint.append(f"{int(np.sum(flags[cut_ids] & 1 == 0))} CUT outlines are not closed (70 & 1)")
    pid = np.full(n, None, dtype=object)
    xd = in_cut & (c == 1000)
    app = in_cut & (c == 1001)
    ok_app = np.zeros(n, dtype=bool)
    ok_app[ent[app][pick(np.flatnonzero(app) + a) == APPID]] = True
    pid[ent[xd]] = pick(np.flatnonzero(xd) + a)
    order = np.argsort(owner, kind="stable")
    P = np.stack([xs, ys], axis=1)[order]
    bounds = np.concatenate([[0], np.cumsum(count)])
    out = {}
    for j, e in enumerate(cut_ids.tolist()):
        if ok_app[e] and pid[e] is not None:
            out[str(pid[e])] = P[bounds[j]:bounds[j + 1]]
    facts = {"lint": lint, "audit_errors": len(lint), "units": units, "texts": texts,
             "reader": "independent DXF text reader"}
    if not sheets:
        return out, facts
    sheet = (etype == "LWPOLYLINE") & (layer == "SHEET")              # the stock sheets' frames, in order
    in_sheet = sheet[ent]
    frames = np.zeros((0, 4, 2))
    if sheet.any():
        fx = numbers(at(in_sheet & (c == 10)), float, "a sheet corner")
        fy = numbers(at(in_sheet & (c == 20)), float, "a sheet corner")
        if fx.size == fy.size == 4 * int(sheet.sum()) and np.isfinite(fx).all() and np.isfinite(fy).all():
            frames = np.stack([fx, fy], axis=1).reshape(-1, 4, 2)
        else:
            lint.append("a SHEET frame is not 4 finite corners")
    labels = pick(np.flatnonzero(((etype == "TEXT") & (layer == "SHEET"))[ent] & (c == 1)) + a).tolist()
    return out, dict(facts, audit_errors=len(lint), sheets=frames, sheet_labels=labels)


def _strict(buf: np.ndarray, data: bytes, codes: np.ndarray, vs: np.ndarray, ve: np.ndarray, path,
            kernel=None) -> None:
    """Refuse (:class:`ExportError` naming the file, the line and the value) the first pair of the file
    ezdxf's loader refuses, or whose number is not finite: a value of a :data:`NUMBER_CODES` code that is
    not a finite decimal number, an x coordinate (:data:`POINT_CODES`) not followed by its y (comments,
    999, between them skipped), binary data (:data:`BINARY_CODES`) that is not hexadecimal.  The numbers
    are read by ``kernel.numbers`` (:mod:`fabricate.export._dxf_kernel`) or by :data:`NUMBER` and
    ``np.fromstring``: the same pair either way."""
    n = len(codes)
    if not n:
        return
    c = np.where((codes >= 0) & (codes < len(IS_NUMBER)), codes, 0)          # other codes: strings
    bad: list[tuple[int, str]] = []                                        # (pair, why)
    rows = np.flatnonzero(IS_NUMBER[c])
    first = _first_not_number(buf, data, vs, ve, rows, kernel)
    if first is not None:
        p = int(rows[first])
        bad.append((p, f"line {2 * p + 2}: {_shown(data, vs[p], ve[p])} (group code {int(codes[p])}): expected "
                       "a finite number"))
    kept = np.flatnonzero(codes != 999)                                    # ezdxf skips comments
    xs = np.flatnonzero(IS_POINT[c[kept]])
    after = np.minimum(xs + 1, len(kept) - 1)
    lost = xs[(xs + 1 >= len(kept)) | (codes[kept[after]] != codes[kept[xs]] + 10)]
    if lost.size:
        p, q = int(kept[lost[0]]), int(lost[0]) + 1
        x = int(codes[p])
        bad.append((p, f"line {2 * p + 1}: the x coordinate (group code {x}) is followed by "
                       + (f"group code {int(codes[kept[q]])} (line {2 * int(kept[q]) + 1})" if q < len(kept)
                          else "the end of the file") + f", not by its y (group code {x + 10})"))
    for p in np.flatnonzero(IS_BINARY[c]).tolist():
        try:
            binascii.unhexlify(data[int(vs[p]):int(ve[p])])
        except (binascii.Error, ValueError):
            bad.append((p, f"line {2 * p + 2}: {_shown(data, vs[p], ve[p])} (group code {int(codes[p])}): "
                           "expected hexadecimal binary data"))
            break
    if bad:
        raise ExportError(f"{path}: {min(bad)[1]}; a DXF reader (ezdxf) refuses the file")


def _shown(data: bytes, a, b) -> str:
    """A value as the message quotes it: decoded, at most 40 characters."""
    text = data[int(a):int(b)].decode("utf-8", "replace")
    return repr(text if len(text) <= 40 else text[:40] + "...")


def _first_not_number(buf: np.ndarray, data: bytes, vs: np.ndarray, ve: np.ndarray, rows: np.ndarray,
                      kernel=None) -> int | None:
    """The first ``t`` such that the value of pair ``rows[t]`` is not a finite decimal number
    (:data:`NUMBER`, and ``float`` of it finite), None when all are."""
    if not len(rows):
        return None
    if kernel is not None:
        first, near = kernel.numbers(buf, vs, ve, rows)    # near the largest double: read here, exactly
        for t in near.tolist():
            if not np.isfinite(float(data[int(vs[rows[t]]):int(ve[rows[t]])])):
                return t
        return None if first < 0 else int(first)
    text = b"\n".join([data[a:b] for a, b in zip(vs[rows].tolist(), ve[rows].tolist())]) + b"\n"
    good = text[:_NUMBERS.match(text).end()]                # the values up to the first that is none
    n_good = good.count(b"\n")
    with filtered("ignore", DeprecationWarning):
        x = np.fromstring(good, dtype=np.float64, sep=" ") if n_good else np.zeros(0)
    if x.size != n_good:                                    # each a number, one a line: not seen
        x = np.array([float(v) for v in good.split(b"\n")[:-1]])
    inf = np.flatnonzero(~np.isfinite(x))
    if inf.size:
        return int(inf[0])
    return None if n_good == len(rows) else n_good
