"""A fast reader of the meshes of a 3MF package, for the full check (independent of the writer).

``read_3mf_text(path)`` checks that ``3D/3dmodel.model`` is well-formed XML
with expat (in C, no tree is built), then reads every ``<object>``'s name,
``<vertex x= y= z=>`` and ``<triangle v1= v2= v3=>``: one regular expression matches each
``<vertices>`` (``<triangles>``) block whole, made of nothing but such elements (as this project
writes them: attributes in that order, one space apart), and numpy reads the numbers of all
blocks at once (the tag and attribute names blanked out of their joined text).
Each object's vertex and triangle counts are those of its own text (the block between its
``<object`` tag and the next; every ``<vertex`` of the model must lie in a matched block), so no
vertex can be given to the wrong object; a triangle index beyond its object's vertices is an error.  A model
whose elements are written otherwise (attributes in another order, other
quoting) is read by :func:`read_3mf` (ElementTree), below.
"""
from __future__ import annotations

import re
import zipfile
import zlib
from pathlib import Path
from xml.parsers import expat
from xml.sax.saxutils import unescape

import numpy as np

from optimize.errors import ExportError
from optimize.warnfilter import filtered

CORE = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"

MODEL = "3D/3dmodel.model"
MAX_UNPACK = 100
"""A 3MF's model may unpack to at most this many times the file's bytes, plus :data:`UNPACK_FLOOR`
(this project's files unpack to 4-5 times; a deflated run of one byte, to 1,000 times: 20 MB of it
would take 20 GB to read)."""
UNPACK_FLOOR = 64 << 20


def open_model(z: zipfile.ZipFile, path):
    """The model of 3MF ``z`` (at ``path``), opened for reading; ExportError when it unpacks to more than
    :data:`MAX_UNPACK` times the file (the reader stops at the size the archive declares, so this bounds
    the memory it takes)."""
    size = z.getinfo(MODEL).file_size
    packed = Path(path).stat().st_size
    if size > MAX_UNPACK * packed + UNPACK_FLOOR:
        raise ExportError(f"{path}: {MODEL} unpacks to {size / 2**20:.0f} MiB from a {packed / 2**20:.1f} MiB "
                          f"file; expected at most {MAX_UNPACK} times the file (+ {UNPACK_FLOOR >> 20} MiB)")
    return z.open(MODEL)
_NUM = rb'[-+0-9.eE]+'
VERTICES = re.compile(rb'<vertices>((?:\s*<vertex x="' + _NUM + rb'" y="' + _NUM + rb'" z="' + _NUM
                      + rb'"/>)*)\s*</vertices>')
TRIANGLES = re.compile(rb'<triangles>((?:\s*<triangle v1="\d+" v2="\d+" v3="\d+"/>)*)\s*</triangles>')
LITERALS = {"vertex": (b'<vertex x="',), "triangle": (b'<triangle v1="', b'" v2="', b'" v3="')}
KEEP = {"vertex": b"-+0123456789.eE", "triangle": b"0123456789"}
BLANK = {what: bytes(c if c in keep else 32 for c in range(256)) for what, keep in KEEP.items()}
OBJECT = re.compile(rb'<object([^>]*)')
NAME = re.compile(rb'\sname="([^"]*)"')


def _numbers(text: bytes, count: int, dtype, what: str, path) -> np.ndarray:
    """``(count, 3)`` numbers of the elements written in ``text`` (the joined insides of the
    ``<vertices>`` or ``<triangles>`` blocks matched by :data:`VERTICES` / :data:`TRIANGLES`): the
    literal text of the element's tag and attribute names is blanked (replaced, then every byte a
    number cannot hold turned into a space) and numpy reads the numbers left, in order."""
    if what == "triangle" and count:
        T = _indices(text)
        if T is not None:
            if len(T) != 3 * count:
                raise ExportError(f"{path}: a {what} of the 3MF model has a value that is not a number")
            return T.reshape(-1, 3)
    for lit in LITERALS[what]:
        text = text.replace(lit, b" ")
    text = text.translate(BLANK[what])
    with filtered("ignore", DeprecationWarning):
        try:
            x = np.fromstring(text, dtype=np.float64, sep=" ") if count else np.zeros(0)
        except ValueError:
            x = np.zeros(0)
    if x.size != 3 * count or not np.isfinite(x).all():
        raise ExportError(f"{path}: a {what} of the 3MF model has a value that is not a number")
    return x.reshape(-1, 3).astype(dtype)


def _indices(text: bytes) -> np.ndarray | None:
    """``(k,)`` int64 vertex indices written in ``text`` (the joined ``<triangles>`` blocks, made of
    nothing but ``<triangle v1="i" v2="j" v3="k"/>``): the digits between each pair of quotes, read
    with numpy; None when a number has more than 15 digits (then read as a float, as numpy's parser
    does, exact up to there)."""
    b = np.frombuffer(text, np.uint8)
    quote = np.flatnonzero(b == ord('"'))
    start, n = quote[0::2] + 1, quote[1::2] - quote[0::2] - 1          # each value: [start, start + n)
    if len(n) and n.max() > 15:
        return None
    out = (b[start] - 48).astype(np.int64)
    for j in range(1, int(n.max(initial=0))):                          # digit j of every number that has one
        m = np.flatnonzero(n > j)
        out[m] = out[m] * 10 + (b[start[m] + j] - 48)
    return out


def _blocks(pattern, model: bytes, starts: np.ndarray) -> tuple[bytes, np.ndarray] | None:
    """The joined insides of the ``<vertices>`` (or ``<triangles>``) blocks matched by ``pattern``
    and the element count ``(objects,)`` of each object (its block between its ``<object`` and the
    next: the ``<`` in it, as a matched block holds nothing but the elements); None when an object
    has two blocks or a block lies before the first object."""
    found = [(m.start(), m.group(1)) for m in pattern.finditer(model)]
    owner = np.searchsorted(starts, np.array([p for p, _ in found], dtype=np.int64), side="right") - 1
    if len(owner) and (owner.min() < 0 or (np.diff(owner) <= 0).any()):
        return None
    blocks = [b for _, b in found]
    text = b" ".join(blocks)
    ends = np.cumsum(np.array([len(b) + 1 for b in blocks], dtype=np.int64))
    lt = np.flatnonzero(np.frombuffer(text, np.uint8) == ord("<"))
    n = np.zeros(len(starts), dtype=np.int64)
    n[owner] = np.diff(np.concatenate([[0], np.searchsorted(lt, ends)]))
    return text, n


def read_3mf_text(path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """``{name: (V (nv, 3) float, T (t, 3) int)}`` of every object (vertices as stored)."""
    path = Path(path)
    try:
        with zipfile.ZipFile(path) as z, open_model(z, path) as fh:
            model = fh.read()
    except (OSError, KeyError, EOFError, RuntimeError, NotImplementedError, zipfile.BadZipFile, zlib.error) as exc:
        raise ExportError(f"{path}: not a readable 3MF file ({exc})") from None   # damaged packed data too
    try:
        expat.ParserCreate().Parse(model, True)
    except expat.ExpatError as exc:
        raise ExportError(f"{path}: {MODEL} is not well-formed XML ({exc})") from None
    tags = [(m.start(), m.group(1)) for m in OBJECT.finditer(model)]
    starts = np.array([p for p, _ in tags], dtype=np.int64)
    vb, tb = _blocks(VERTICES, model, starts), _blocks(TRIANGLES, model, starts)
    if vb is None or tb is None or int(vb[1].sum()) != model.count(b"<vertex ") \
            or int(tb[1].sum()) != model.count(b"<triangle "):
        return read_3mf(path)                       # elements written otherwise: the tree reader
    nv, nt = vb[1], tb[1]
    V = _numbers(vb[0], int(nv.sum()), np.float64, "vertex", path)
    T = _numbers(tb[0], int(nt.sum()), np.int64, "triangle", path)
    vo = np.concatenate([[0], np.cumsum(nv)])
    to = np.concatenate([[0], np.cumsum(nt)])
    limit = np.repeat(nv, nt)
    if T.size and (T.max(axis=1) >= limit).any():
        k = int(np.searchsorted(to, np.argmax(T.max(axis=1) >= limit), side="right") - 1)
        raise ExportError(f"{path}: object {k + 1} of the 3MF model has a triangle index beyond its "
                          f"{int(nv[k])} vertices")
    out = {}
    for k, (_, head) in enumerate(tags):
        m = NAME.search(head)
        name = m.group(1).decode("utf-8", "replace") if m else None
        if name is not None and "&" in name:
            name = unescape(name, {"&quot;": '"', "&apos;": "'"})
        out[name] = (V[vo[k]:vo[k + 1]], T[to[k]:to[k + 1]])
    return out


def read_3mf(path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """``{name: (V (nv, 3) float, T (t, 3) int)}`` of every object of a 3MF file (vertices as stored)."""
    import xml.etree.ElementTree as ET

    ns = f"{{{CORE}}}"
    out = {}
    try:
        with zipfile.ZipFile(path) as z, open_model(z, path) as fh:
            for _, el in ET.iterparse(fh, events=("end",)):
                if el.tag != ns + "object":
                    continue
                verts = el.find(f"{ns}mesh/{ns}vertices")
                tris = el.find(f"{ns}mesh/{ns}triangles")
                V = np.array([[float(v.get("x")), float(v.get("y")), float(v.get("z"))] for v in verts],
                             dtype=float).reshape(-1, 3)
                T = np.array([[int(t.get("v1")), int(t.get("v2")), int(t.get("v3"))] for t in tris],
                             dtype=np.int64).reshape(-1, 3)
                out[el.get("name")] = (V, T)
                el.clear()
    except (OSError, KeyError, zipfile.BadZipFile, ET.ParseError) as exc:
        raise ExportError(f"{path}: not a readable 3MF file ({exc})") from None
    return out
