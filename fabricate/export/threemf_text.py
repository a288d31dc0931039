"""A fast reader of the meshes of a 3MF package, for the full check (independent of the writer).

``read_3mf_text(path)`` checks that ``3D/3dmodel.model`` is well-formed XML
with expat (in C, no tree is built), then reads every ``<object>``'s name,
``<vertex x= y= z=>`` and ``<triangle v1= v2= v3=>`` with one regular
expression per element type over the whole model (as this project writes them: attributes in
that order, one space apart) and numpy for the numbers.
Each object's vertex and triangle counts are those of its own text (counted
between its ``<object`` tags), so no vertex can be given to the wrong
object; a triangle index beyond its object's vertices is an error.  A model
whose elements are written otherwise (attributes in another order, other
quoting) is read by :func:`fabricate.export.threemf.read_3mf` (ElementTree).
"""
from __future__ import annotations

import re
import warnings
import zipfile
from pathlib import Path
from xml.parsers import expat
from xml.sax.saxutils import unescape

import numpy as np

from optimize.errors import ExportError

MODEL = "3D/3dmodel.model"
_NUM = rb'[-+0-9.eE]+'
VERTEX = re.compile(rb'<vertex x="(' + _NUM + rb'" y="' + _NUM + rb'" z="' + _NUM + rb')"/>')
TRIANGLE = re.compile(rb'<triangle v1="(\d+" v2="\d+" v3="\d+)"/>')
SEPARATORS = {"vertex": (b'" y="', b'" z="'), "triangle": (b'" v2="', b'" v3="')}
NAME = re.compile(rb'\sname="([^"]*)"')


def _numbers(groups: list[bytes], dtype, what: str, path) -> np.ndarray:
    """``(n, 3)`` numbers of the elements' three attribute values (one match each: ``1" y="2" z="3``)."""
    a, b = SEPARATORS[what]
    text = b" ".join(groups).replace(a, b" ").replace(b, b" ")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        try:
            x = np.fromstring(text, dtype=np.float64, sep=" ") if text else np.zeros(0)
        except ValueError:
            x = np.zeros(0)
    if x.size != 3 * len(groups) or not np.isfinite(x).all():
        raise ExportError(f"{path}: a {what} of the 3MF model has a value that is not a number")
    return x.reshape(-1, 3).astype(dtype)


def read_3mf_text(path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """``{name: (V (nv, 3) float, T (t, 3) int)}`` of every object (vertices as stored)."""
    path = Path(path)
    try:
        with zipfile.ZipFile(path) as z:
            model = z.read(MODEL)
    except (OSError, KeyError, zipfile.BadZipFile) as exc:
        raise ExportError(f"{path}: not a readable 3MF file ({exc})") from None
    try:
        expat.ParserCreate().Parse(model, True)
    except expat.ExpatError as exc:
        raise ExportError(f"{path}: {MODEL} is not well-formed XML ({exc})") from None
    chunks = model.split(b"<object")[1:]
    nv = np.array([c.count(b"<vertex ") for c in chunks], dtype=np.int64)
    nt = np.array([c.count(b"<triangle ") for c in chunks], dtype=np.int64)
    verts, tris = VERTEX.findall(model), TRIANGLE.findall(model)
    if len(verts) != int(nv.sum()) or len(tris) != int(nt.sum()):
        from .threemf import read_3mf

        return read_3mf(path)                       # elements written otherwise: the tree reader
    V = _numbers(verts, np.float64, "vertex", path)
    T = _numbers(tris, np.int64, "triangle", path)
    vo = np.concatenate([[0], np.cumsum(nv)])
    to = np.concatenate([[0], np.cumsum(nt)])
    limit = np.repeat(nv, nt)
    if T.size and (T.max(axis=1) >= limit).any():
        k = int(np.searchsorted(to, np.argmax(T.max(axis=1) >= limit), side="right") - 1)
        raise ExportError(f"{path}: object {k + 1} of the 3MF model has a triangle index beyond its "
                          f"{int(nv[k])} vertices")
    out = {}
    for k, c in enumerate(chunks):
        m = NAME.search(c, 0, c.find(b">"))
        name = unescape(m.group(1).decode("utf-8", "replace"), {"&quot;": '"', "&apos;": "'"}) if m else None
        out[name] = (V[vo[k]:vo[k + 1]], T[to[k]:to[k + 1]])
    return out
