"""3MF (3D Manufacturing Format, core spec): one named mesh object per part, coloured by kind.

Written directly (zip + XML): ``3D/3dmodel.model`` holds one ``<object>``
per part named by its id, with the same triangles as the STL, vertices
relative to the local origin (``%.12g`` mm) and a build item whose transform
puts the origin back.  Colours are ``basematerials`` (glass, steel, node, and the interlayers of
laminated glass: ``PVB interlayer``).
"""
from __future__ import annotations

import time
import zipfile
from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np

from optimize.atomic import atomic_path
from optimize.errors import write_error

from ..cad.parts import COLOURS, KINDS
from .meshes import group_triangles, validate_manifold
from .threemf_text import CORE, MODEL, open_model, read_3mf  # noqa: F401 - read_3mf re-exported

CONTENT_TYPES = ('<?xml version="1.0" encoding="UTF-8"?>\n'
                 '<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">'
                 '<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>'
                 '<Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>'
                 '</Types>\n')
RELS = ('<?xml version="1.0" encoding="UTF-8"?>\n'
        '<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">'
        '<Relationship Target="/3D/3dmodel.model" Id="rel0" '
        'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>\n')
MATERIAL = {"panel": "glass", "beam": "steel", "node": "node steel"}
INTERLAYER_COLOUR = "#F2EBD9"
"""A glass unit's interlayer (PVB, SGP) is a base material of its own."""


def _hex(rgb) -> str:
    return "#" + "".join(f"{round(255 * c):02X}" for c in rgb)


_U = np.uint64
_POW10 = 10.0 ** np.arange(-2, 19)                    # 10^k at k + 2: exact for 0 <= k <= 16
_DIGITS4 = np.frombuffer(b"".join(b"%04d" % i for i in range(10000)), dtype="<u4").astype(np.uint64)
_LOW = np.array([(1 << (8 * min(k, 8))) - 1 for k in range(17)], dtype=np.uint64)      # bytes < k: word 0
_HIGH = np.array([(1 << (8 * max(k - 8, 0))) - 1 for k in range(17)], dtype=np.uint64)  # and word 1
_ZEROS = np.array([int.from_bytes(b"0" * k, "little") for k in range(9)], dtype=np.uint64)
_DOT0 = np.array([0x2E << (8 * k) if k < 8 else 0 for k in range(17)], dtype=np.uint64)  # "." at byte k
_DOT1 = np.array([0x2E << (8 * (k - 8)) if 8 <= k < 16 else 0 for k in range(17)], dtype=np.uint64)


def g12_words(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``"%.12g" % v`` of every value of ``x (...)`` float64: ``sign (...) uint8`` (``-`` or NUL) and
    ``text (..., 3) uint64``, the other characters as 24 bytes (little-endian) padded with NUL.

    A number ``d.dddddddddddd x 10^e`` with ``-4 <= e <= 11`` is written from its 12 digits
    (``rint(|v| 10^(11 - e))``: the product has one rounding, below 6.1e-5 under 1e12, so its
    rint is the correctly rounded one unless it is within 2e-4 of a half, which is left to
    Python), without trailing zeros, with ``0.`` and ``-e - 1`` zeros before them when
    ``e < 0``; every other value (exponent notation, inf, nan, a near-half) is formatted by Python.
    """
    shape, x = np.shape(x), np.asarray(x, dtype=np.float64).reshape(-1)
    ax = np.abs(x)
    ok = np.isfinite(x) & (ax > 0)
    safe = np.where(ok, ax, 1.0)
    e = np.floor((np.frexp(safe)[1] - 1) * np.log10(2.0)).astype(np.int64)   # the exponent or one less
    np.clip(e, -4, 13, out=e)
    e += safe * _POW10[13 - e] >= 1e12
    np.clip(e, -4, 13, out=e)
    y = safe * _POW10[13 - e]                               # 1e11 <= y < 1e12, one rounding
    m = np.rint(y)
    python = ok & ((np.abs(y - np.floor(y) - 0.5) < 2e-4) | (y < 1e11) | (y >= 1e12))
    up = m >= 1e12                                          # 999999999999.5 -> 1e+12
    m[up] = 1e11
    e += up
    python |= ~np.isfinite(x) | (ok & ((e < -4) | (e > 11)))
    plain = python | ~ok                                    # zeros: "0" (the sign byte: "-0")
    m[plain], e[plain] = 0, 0
    hi, lo = np.divmod(m.astype(np.int64), 100000000)
    mid, lo = np.divmod(lo, 10000)
    w0, w1 = _DIGITS4[hi] | (_DIGITS4[mid] << _U(32)), _DIGITS4[lo]   # digit i at byte i (8 + 4 digits)
    b0, b1 = np.frexp((w0 ^ _ZEROS[8]).astype(np.float64))[1], np.frexp((w1 ^ _ZEROS[4]).astype(np.float64))[1]
    nd = np.where(b1 > 0, 8 + (b1 + 7) // 8, (b0 + 7) // 8)  # digits up to the last one not 0 (bit lengths)
    nd[plain] = 1
    small = np.flatnonzero(e < 0)                           # 0.000ddd: the digits s = -e places on
    if len(small):
        s = -e[small]
        sh = (8 * s).astype(np.uint64)
        w1[small] = (w1[small] << sh) | (w0[small] >> (_U(64) - sh))
        w0[small] = (w0[small] << sh) | _ZEROS[s]
        nd[small] += s
    L = np.maximum(e + 1, 1)                                # digits before the point
    keep = np.maximum(nd, L)
    w0 &= _LOW[keep]
    w1 &= _HIGH[keep]
    low, high = _LOW[L], _HIGH[L]
    a0, a1 = w0 & ~low, w1 & ~high                          # the digits after the point, moved one on
    dot = np.where(nd > L, L, 16)
    text = np.empty((len(x), 3), dtype=np.uint64)
    text[:, 0] = (w0 & low) | _DOT0[dot] | (a0 << _U(8))
    text[:, 1] = (w1 & high) | _DOT1[dot] | (a1 << _U(8)) | (a0 >> _U(56))
    text[:, 2] = a1 >> _U(56)
    sign = np.signbit(x).view(np.uint8) * np.uint8(45)
    for i in np.flatnonzero(python):
        sign[i], text[i] = 0, np.frombuffer((b"%.12g" % x[i]).ljust(24, b"\0"), dtype="<u8")
    return sign.reshape(shape), text.reshape(shape + (3,))


_VERTEX = np.dtype([("a", "S11"), ("sx", "u1"), ("x", "<u8", 3), ("b", "S5"), ("sy", "u1"), ("y", "<u8", 3),
                    ("c", "S5"), ("sz", "u1"), ("z", "<u8", 3), ("d", "S3")])
"""One ``<vertex x="..." y="..." z="..."/>``: each number a sign byte and 24 text bytes (:func:`g12_words`),
padded with NUL bytes, which are then left out."""
BLOCK = 1 << 16
"""Vertices formatted at a time (memory)."""


def group_text(group, origin: np.ndarray, first_id: int, pindex: int):
    """The ``<object>`` elements of the group's parts (ids from ``first_id``), as uint8 arrays (UTF-8):
    vertices ``%.12g`` relative to ``origin`` (:func:`g12_words`), fan triangles."""
    X, T = group_triangles(group, origin)
    p, nv, _ = X.shape
    tail = ("</vertices><triangles>" + "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in T.tolist())
            + "</triangles></mesh></object>\n").encode()
    step = max(1, BLOCK // nv)
    for i0 in range(0, p, step):
        ids = group.ids[i0:i0 + step]
        heads = [f'<object id="{first_id + i0 + i}" name="{pid}" type="model" pid="1" pindex="{pindex}">'
                 "<mesh><vertices>".encode() for i, pid in enumerate(ids)]
        rec = np.empty(len(ids), dtype=[("h", f"S{max(map(len, heads))}"), ("v", _VERTEX, nv), ("t", f"S{len(tail)}")])
        rec["h"], rec["t"] = heads, tail
        v = rec["v"]
        v["a"], v["b"], v["c"], v["d"] = b'<vertex x="', b'" y="', b'" z="', b'"/>'
        for k, name in enumerate("xyz"):
            v["s" + name], v[name] = g12_words(X[i0:i0 + step, :, k])
        raw = rec.view(np.uint8)
        yield raw[raw != 0]


def write_3mf(parts, path, *, origin: np.ndarray | None = None) -> dict:
    """Write a 3MF package (atomic) after checking every part with manifold3d.

    Returns facts: ``file, bytes, objects, triangles, origin_mm, seconds``.
    """
    t0 = time.perf_counter()
    path = Path(path)
    origin = parts.local_origin() if origin is None else np.asarray(origin, dtype=float)
    validate_manifold(parts, origin)
    tx = " ".join(f"{x:.17g}" for x in origin)
    extra = sorted({g.material for g in parts.groups if g.material})   # a glass unit's interlayers
    head = ('<?xml version="1.0" encoding="UTF-8"?>\n'
            f'<model unit="millimeter" xml:lang="en-US" xmlns="{CORE}">\n'
            '<metadata name="Application">conical-fab</metadata>\n'
            f'<metadata name="Description">{len(parts)} parts (P panel, B beam, N node); vertices relative '
            f'to the origin {escape(tx)} mm, restored by each build item transform</metadata>\n'
            '<resources>\n<basematerials id="1">'
            + "".join(f'<base name="{MATERIAL[k]}" displaycolor="{_hex(COLOURS[k])}"/>' for k in KINDS)
            + "".join(f'<base name="{escape(m)} interlayer" displaycolor="{INTERLAYER_COLOUR}"/>' for m in extra)
            + "</basematerials>\n")
    n_tri, object_id = 0, 2
    try:
        with atomic_path(path) as tmp, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as z:
            z.writestr("[Content_Types].xml", CONTENT_TYPES)
            z.writestr("_rels/.rels", RELS)
            with z.open(MODEL, "w") as fh:
                fh.write(head.encode())
                for g in parts.groups:
                    pindex = len(KINDS) + extra.index(g.material) if g.material else KINDS.index(g.kind)
                    for text in group_text(g, origin, object_id, pindex):
                        fh.write(text)
                    object_id += len(g)
                    n_tri += len(g) * sum(len(f) - 2 for f in g.faces)
                transform = f' transform="1 0 0 0 1 0 0 0 1 {tx}"' if np.any(origin) else ""
                fh.write(("</resources>\n<build>\n"
                          + "".join(f'<item objectid="{i}"{transform}/>\n' for i in range(2, object_id))
                          + "</build>\n</model>\n").encode())
    except OSError as exc:
        raise write_error(path, "3MF file", exc) from exc
    return {"file": path.name, "bytes": path.stat().st_size, "objects": object_id - 2, "triangles": n_tri,
            "origin_mm": origin.tolist(), "seconds": time.perf_counter() - t0}
