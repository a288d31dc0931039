"""Stanford PLY: ``ascii``, ``binary_little_endian`` and ``binary_big_endian``.

Read: the ``vertex`` element's ``x y z`` (any numeric type; other properties
skipped by their size), the ``face`` element's ``vertex_indices`` (or
``vertex_index``) list with any integer count and index types; any other
element is skipped.  Binary elements are read with one ``numpy.frombuffer``
when their lists have a constant length (quads, triangles), record by record
otherwise.  Messages give the header line, the body line (ascii) or the byte
offset and element index (binary).

Write: binary little-endian by default (vertices as ``double``, faces as
``list uchar int``; ``uint`` counts past 255 corners), or ascii with ``%.17g``.
"""
from __future__ import annotations

import re
import struct
from dataclasses import dataclass, field

import numpy as np

from ...errors import MeshError
from .common import (
    BOM,
    Parsed,
    Tokens,
    declared,
    face_lists,
    fail,
    is_count,
    one_line,
    show,
    to_floats,
    to_ints,
    where,
)

ENCODINGS = ("ascii", "binary_little_endian", "binary_big_endian")
_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2",
          "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
          "float": "f4", "float32": "f4", "double": "f8", "float64": "f8"}
_END = re.compile(rb"(?m)^[ \t]*end_header[ \t]*(\r\n|\n|\r|$)")
_FACE_LISTS = ("vertex_indices", "vertex_index")


@dataclass
class Prop:
    """A property: scalar (``code``) or list (``count_code``, ``code`` of the items)."""

    name: str
    code: str
    count_code: str | None = None
    line: int = 0


@dataclass
class Element:
    name: str
    count: int
    line: int
    props: list[Prop] = field(default_factory=list)

    def prop(self, name: str) -> int | None:
        return next((j for j, p in enumerate(self.props) if p.name == name), None)


# -- header -------------------------------------------------------------------
def parse_header(data: bytes, path: str) -> tuple[str, list[Element], int, int]:
    """(encoding, elements, byte offset of the body, line number of the first body line)."""
    first = data[:64].removeprefix(BOM).split(b"\n", 1)[0].strip()
    if first != b"ply":
        raise fail(path, 1, f"found {first[:20]!r}, expected 'ply' on the first line")
    m = _END.search(data)
    if m is None:
        raise fail(path, None, "no 'end_header' line, expected the header to end with it")
    lines = data[: m.start()].decode("utf-8", errors="replace").splitlines()
    encoding, elements = None, []
    for no, line in enumerate(lines[1:], start=2):
        w = line.split()
        if not w or w[0] in ("comment", "obj_info"):
            continue
        if w[0] == "format":
            if len(w) != 3 or w[1] not in ENCODINGS:
                raise fail(path, no, f"'{line.strip()}', expected 'format ascii|binary_little_endian|"
                                     "binary_big_endian 1.0'")
            encoding = w[1]
        elif w[0] == "element":
            if len(w) != 3 or not is_count(w[2]):
                raise fail(path, no, f"'{line.strip()}', expected 'element NAME COUNT'")
            elements.append(Element(w[1], int(w[2]), no))
        elif w[0] == "property":
            if not elements:
                raise fail(path, no, "a property before any element, expected 'element NAME COUNT' first")
            elements[-1].props.append(_prop(w, line, no, path))
        else:
            raise fail(path, no, f"'{show(line.strip())}', expected format, element, property, "
                                 "comment or end_header")
    if encoding is None:
        raise fail(path, 2, "no 'format' line, expected 'format ascii 1.0' or a binary format")
    body_line = data[: m.end()].count(b"\n") + 1
    _check_counts(elements, encoding, len(data) - m.end(), path)
    return encoding, elements, m.end(), body_line


def _check_counts(elements: list[Element], encoding: str, available: int, path: str) -> None:
    """Every element count against the bytes after the header, before anything is allocated:
    a binary record takes at least its scalars and list counts, an ascii record at least two
    bytes (a digit and a separator) per property."""
    need = 0
    for el in elements:
        if encoding == "ascii":
            unit = 2 * len(el.props)
        else:
            unit = sum(np.dtype(p.count_code or p.code).itemsize for p in el.props)
        declared(path, el.line, f"element '{el.name}'", el.count, unit, available - need + (encoding == "ascii"),
                 where_from="follow the header (after the elements before it)" if need else "follow the header")
        need += el.count * unit


def _prop(w: list[str], line: str, no: int, path: str) -> Prop:
    if len(w) == 3 and w[1] in _TYPES:
        return Prop(w[2], _TYPES[w[1]], None, no)
    if len(w) == 5 and w[1] == "list" and w[2] in _TYPES and w[3] in _TYPES:
        if _TYPES[w[2]][0] == "f":
            raise fail(path, no, f"list count type '{w[2]}', expected an integer type")
        return Prop(w[4], _TYPES[w[3]], _TYPES[w[2]], no)
    raise fail(path, no, f"'{show(line.strip(), 60)}', expected 'property TYPE NAME' or 'property list "
                         f"COUNT_TYPE ITEM_TYPE NAME' with types {sorted(set(_TYPES))}")


def _mesh_elements(elements: list[Element], path: str) -> tuple[Element, Element, list[int], int]:
    """The vertex and face elements, the x/y/z property slots, the face list slot."""
    byname = {e.name: e for e in elements}
    if "vertex" not in byname:
        raise fail(path, None, "no 'vertex' element in the header, expected 'element vertex N'")
    if "face" not in byname:
        raise fail(path, None, "no 'face' element in the header, expected 'element face M' "
                               "(a point cloud is not a mesh)")
    ve, fe = byname["vertex"], byname["face"]
    xyz = [ve.prop(c) for c in "xyz"]
    if None in xyz or any(ve.props[j].count_code for j in xyz):
        raise fail(path, ve.line, f"vertex properties {[p.name for p in ve.props]}, expected "
                                  "scalar x, y and z")
    slot = next((fe.prop(n) for n in _FACE_LISTS if fe.prop(n) is not None), None)
    if slot is None or fe.props[slot].count_code is None:
        raise fail(path, fe.line, f"face properties {[p.name for p in fe.props]}, expected a list "
                                  "'vertex_indices'")
    if fe.props[slot].code[0] == "f":
        raise fail(path, fe.props[slot].line, "face indices of a float type, expected an integer type")
    return ve, fe, xyz, slot


def parse_ply(data: bytes, path: str) -> Parsed:
    """Parse PLY ``data`` (read from ``path``, used in messages) into a :class:`Parsed`."""
    encoding, elements, body, body_line = parse_header(data, path)
    ve, fe, xyz, slot = _mesh_elements(elements, path)
    if encoding == "ascii":
        return _parse_ascii(data[body:].decode("utf-8", errors="replace"), body_line, elements,
                            ve, fe, xyz, slot, path)
    endian = "<" if encoding == "binary_little_endian" else ">"
    pos, got = body, {}
    for el in elements:
        if not el.props:
            continue  # records of zero bytes: nothing to read
        if el is ve or el is fe:
            got[el.name], pos = _binary_element(data, pos, el, endian, path)
        else:
            pos = _binary_element(data, pos, el, endian, path)[1]
    rest = data[pos:]
    if rest.strip():
        raise fail(path, pos, f"{len(rest)} byte(s) after the last record of element "
                              f"'{elements[-1].name}' ({_declared(elements)}), expected the end of the "
                              "file (a count in the header too small?)", "byte")
    cols, vstart = got["vertex"]
    V = np.stack([cols[j].astype(np.float64) for j in xyz], axis=1) if ve.count else np.zeros((0, 3))
    fcols, fstart = got["face"]
    flat, sizes = fcols[slot]
    return Parsed(V, flat.astype(np.int64), sizes, vstart, fstart, "byte", 0)


# -- binary -------------------------------------------------------------------
def _binary_element(data: bytes, pos: int, el: Element, endian: str, path: str):
    """Read ``el`` at byte ``pos``: ((columns, record offsets (count,)), next byte).

    A scalar column is a ``(count,)`` array; a list column is ``(flat (c,), sizes (count,))``.
    """
    if not any(p.count_code for p in el.props):
        dt = np.dtype([(f"p{j}", endian + p.code) for j, p in enumerate(el.props)])
        return _fixed(data, pos, el, dt, [None] * len(el.props), path)
    lengths = _first_record_lengths(data, pos, el, endian)
    if lengths is not None:
        fields = []
        for j, p in enumerate(el.props):
            if p.count_code:
                fields.append((f"n{j}", endian + p.count_code))
                fields.append((f"p{j}", endian + p.code, (lengths[j],)))
            else:
                fields.append((f"p{j}", endian + p.code))
        dt = np.dtype(fields)
        if pos + el.count * dt.itemsize <= len(data):
            arr = np.frombuffer(data, dt, el.count, pos)
            if all(np.all(arr[f"n{j}"] == lengths[j]) for j, p in enumerate(el.props) if p.count_code):
                return _fixed(data, pos, el, dt, lengths, path, arr)
    return _records(data, pos, el, endian, path)


def _fixed(data, pos, el, dt, lengths, path, arr=None):
    """Every record ``dt.itemsize`` bytes: one frombuffer call."""
    need = el.count * dt.itemsize
    if pos + need > len(data):
        done = (len(data) - pos) // max(dt.itemsize, 1)
        raise fail(path, len(data), f"file ends inside element '{el.name}' record {done} of "
                                    f"{el.count} (records of {dt.itemsize} bytes from byte {pos}), "
                                    f"expected {el.count} records", "byte")
    if arr is None:
        arr = np.frombuffer(data, dt, el.count, pos)
    cols = []
    for j, k in enumerate(lengths):
        col = arr[f"p{j}"]
        cols.append(col if k is None else (col.reshape(-1), np.full(el.count, k, dtype=np.int64)))
    return (cols, pos + dt.itemsize * np.arange(el.count)), pos + need


def _first_record_lengths(data, pos, el, endian) -> list | None:
    """List lengths of the first record of ``el`` (None where scalar), or None if unreadable."""
    lengths = []
    for p in el.props:
        if p.count_code is None:
            lengths.append(None)
            pos += np.dtype(p.code).itemsize
            continue
        size = np.dtype(p.count_code).itemsize
        if pos + size > len(data) or el.count == 0:
            return None
        k = int(np.frombuffer(data, endian + p.count_code, 1, pos)[0])
        if k < 0 or pos + size + k * np.dtype(p.code).itemsize > len(data):
            return None  # read record by record: it names the bad record
        lengths.append(k)
        pos += size + k * np.dtype(p.code).itemsize
    return lengths


def _records(data, pos, el, endian, path):
    """Record by record (lists of varying length, e.g. mixed n-gons)."""
    scalar = [struct.Struct(endian + _struct_code(p.code)) for p in el.props]
    counts = [struct.Struct(endian + _struct_code(p.count_code)) if p.count_code else None
              for p in el.props]
    items = [[] for _ in el.props]
    sizes = [[] for _ in el.props]
    starts = []
    n = len(data)
    for i in range(el.count):  # variable-length records: each length is in the record
        starts.append(pos)
        for j, c in enumerate(counts):
            if c is None:
                if pos + scalar[j].size > n:
                    raise _truncated(path, n, el, i, starts[-1])
                items[j].append(scalar[j].unpack_from(data, pos)[0])
                pos += scalar[j].size
                continue
            if pos + c.size > n:
                raise _truncated(path, n, el, i, starts[-1])
            k = c.unpack_from(data, pos)[0]
            if k < 0:
                raise fail(path, pos, f"element '{el.name}' record {i} has list length {k}, "
                                      "expected >= 0", "byte")
            pos += c.size
            end = pos + k * scalar[j].size
            if end > n:
                raise _truncated(path, n, el, i, starts[-1], f", whose '{el.props[j].name}' "
                                                             f"list declares {k} items")
            items[j].append(data[pos:end])
            sizes[j].append(k)
            pos = end
    cols = []
    for j, p in enumerate(el.props):
        if counts[j] is None:
            cols.append(np.asarray(items[j]))
        else:
            flat = np.frombuffer(b"".join(items[j]), endian + p.code)
            cols.append((flat, np.asarray(sizes[j], dtype=np.int64)))
    return (cols, np.asarray(starts, dtype=np.int64)), pos


def _struct_code(code: str) -> str:
    return {"i1": "b", "u1": "B", "i2": "h", "u2": "H", "i4": "i", "u4": "I", "f4": "f", "f8": "d"}[code]


def _truncated(path, n, el, i, pos, detail: str = "") -> MeshError:
    return fail(path, n, f"file ends inside element '{el.name}' record {i} of {el.count} "
                         f"(from byte {pos}{detail}), expected {el.count} records", "byte")


# -- ascii --------------------------------------------------------------------
def _parse_ascii(text, body_line, elements, ve, fe, xyz, slot, path) -> Parsed:
    tk = Tokens(text, first_line=body_line, comments=False)
    toks = tk.tokens
    p = 0
    V = np.zeros((0, 3))
    flat = sizes = np.zeros(0, dtype=np.int64)
    vstart = fstart = np.zeros(0, dtype=np.int64)
    for el in elements:
        if not el.props:
            continue  # records without tokens
        if not any(q.count_code for q in el.props):
            width = len(el.props)
            if p + el.count * width > len(toks):
                done = (len(toks) - p) // max(width, 1)
                raise fail(path, tk.line_of(len(toks)), f"file ends after {done} of {el.count} "
                                                        f"'{el.name}' records, expected {el.count}")
            starts = p + width * np.arange(el.count)
            if el is ve:
                idx = (starts[:, None] + np.asarray(xyz)[None, :]).ravel().tolist()
                V = to_floats([toks[i] for i in idx],
                              lambda i, idx=idx: (where(path, tk.line_of(idx[i])), f" (vertex {i // 3})"),
                              "a vertex coordinate").reshape(-1, 3)
                vstart = starts
            p += el.count * width
            continue
        if el is ve:
            raise fail(path, ve.line, "list properties in the vertex element, expected scalars")
        starts, lists, p = _ascii_records(tk, p, el, path)
        if el is fe:
            begin, sizes = lists[slot]
            first = np.repeat(begin, sizes)
            idx = (first + np.arange(len(first)) - np.repeat(np.cumsum(sizes) - sizes, sizes)).tolist()
            flat = to_ints([toks[i] for i in idx], lambda i, idx=idx: (where(path, tk.line_of(idx[i])), ""),
                           "a vertex index")
            fstart = starts
    if p < len(toks):
        raise fail(path, tk.line_of(p), f"'{show(toks[p])}' after the last record of element "
                                        f"'{elements[-1].name}' ({_declared(elements)}), expected the end "
                                        "of the file (a count in the header too small?)")
    return Parsed(V, flat, sizes, tk.line[vstart], tk.line[fstart], "line", 0)


def _declared(elements: list[Element]) -> str:
    """``"4 vertex, 1 face as declared"`` for messages."""
    return ", ".join(f"{el.count} {el.name}" for el in elements) + " as declared"


def _ascii_records(tk: Tokens, p: int, el: Element, path: str):
    """Walk ``el`` record by record: (record starts (count,), per list prop (first item
    token (count,), sizes (count,)), next token)."""
    toks, n = tk.tokens, len(tk.tokens)
    starts = []
    begins = [[] for _ in el.props]
    sizes = [[] for _ in el.props]
    for i in range(el.count):  # records of varying length
        starts.append(p)
        for j, q in enumerate(el.props):
            if p >= n:
                raise fail(path, tk.line_of(n), f"file ends inside '{el.name}' record {i} of "
                                                f"{el.count}, expected {el.count} records")
            if q.count_code is None:
                p += 1
                continue
            t = toks[p]
            if not is_count(t):
                raise fail(path, tk.line_of(p), f"'{show(t)}' starts the '{q.name}' list of "
                                                f"'{el.name}' record {i}, expected a count >= 0")
            k = int(t)
            begins[j].append(p + 1)
            sizes[j].append(k)
            p += 1 + k
    if p > n:
        raise fail(path, tk.line_of(n), f"file ends inside '{el.name}' record {el.count - 1} of "
                                        f"{el.count}, expected {el.count} records")
    lists = [(np.asarray(b, dtype=np.int64), np.asarray(s, dtype=np.int64))
             for b, s in zip(begins, sizes)]
    return np.asarray(starts, dtype=np.int64), lists, p


# -- writing --------------------------------------------------------------------
def format_ply(mesh, encoding: str = "binary_little_endian", comments=()) -> bytes:
    """PLY bytes of ``mesh``: vertices as double, faces as ``list uchar int`` (``uint`` counts
    past 255 corners); ``encoding`` one of :data:`ENCODINGS`."""
    if encoding not in ENCODINGS:
        raise ValueError(f"PLY encoding {encoding!r}, expected one of {ENCODINGS}")
    sizes = np.asarray(mesh.face_sizes, dtype=np.int64)
    count_type = "uchar" if sizes.max(initial=0) <= 255 else "uint"
    extra = "".join(f"comment {c}\n" for c in one_line(comments))
    head = (f"ply\nformat {encoding} 1.0\ncomment written by conical-fab\n{extra}"
            f"element vertex {mesh.n_vertices}\nproperty double x\nproperty double y\n"
            f"property double z\nelement face {mesh.n_faces}\n"
            f"property list {count_type} int vertex_indices\nend_header\n").encode("ascii")
    if encoding == "ascii":
        vs = "".join("%.17g %.17g %.17g\n" % tuple(r) for r in mesh.V.tolist())
        fs = "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in face_lists(mesh, 0))
        return head + (vs + fs).encode("ascii")
    e = "<" if encoding == "binary_little_endian" else ">"
    cb = 1 if count_type == "uchar" else 4
    rec = cb + 4 * sizes
    off = np.cumsum(rec) - rec
    buf = np.zeros(int(rec.sum()), dtype=np.uint8)
    cnt = sizes.astype(e + ("u1" if cb == 1 else "u4")).view(np.uint8).reshape(-1, cb)
    buf[off[:, None] + np.arange(cb)] = cnt
    valid = mesh.F >= 0
    slot = np.nonzero(valid)[1]
    corner = np.repeat(off, sizes) + cb + 4 * slot
    buf[corner[:, None] + np.arange(4)] = mesh.F[valid].astype(e + "i4").view(np.uint8).reshape(-1, 4)
    return head + mesh.V.astype(e + "f8").tobytes() + buf.tobytes()
