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
from optimize.errors import ExportError

from ..cad.parts import COLOURS, KINDS
from .meshes import group_triangles, validate_manifold

CORE = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
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
    return "#" + "".join(f"{int(round(255 * c)):02X}" for c in rgb)


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
    items, n_tri, object_id = [], 0, 2
    try:
        with atomic_path(path) as tmp, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as z:
            z.writestr("[Content_Types].xml", CONTENT_TYPES)
            z.writestr("_rels/.rels", RELS)
            with z.open("3D/3dmodel.model", "w") as fh:
                fh.write(head.encode())
                for g in parts.groups:
                    X, T = group_triangles(g, origin)
                    nv = X.shape[1]
                    vt = "".join(['<vertex x="%.12g" y="%.12g" z="%.12g"/>'] * nv)
                    tris = "<triangles>" + "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>'
                                                   for a, b, c in T.tolist()) + "</triangles></mesh></object>\n"
                    pindex = len(KINDS) + extra.index(g.material) if g.material else KINDS.index(g.kind)
                    out = []
                    for pid, row in zip(g.ids, X.reshape(len(g), -1).tolist()):
                        out.append(f'<object id="{object_id}" name="{pid}" type="model" pid="1" '
                                   f'pindex="{pindex}"><mesh><vertices>')
                        out.append(vt % tuple(row))
                        out.append("</vertices>" + tris)
                        items.append(object_id)
                        object_id += 1
                    n_tri += len(g) * len(T)
                    fh.write("".join(out).encode())
                transform = f' transform="1 0 0 0 1 0 0 0 1 {tx}"' if np.any(origin) else ""
                fh.write(("</resources>\n<build>\n" + "".join(f'<item objectid="{i}"{transform}/>\n' for i in items)
                          + "</build>\n</model>\n").encode())
    except OSError as exc:
        raise ExportError(f"{path}: cannot write the 3MF file ({exc.strerror or exc})") from None
    return {"file": path.name, "bytes": path.stat().st_size, "objects": len(items), "triangles": n_tri,
            "origin_mm": origin.tolist(), "seconds": time.perf_counter() - t0}


def read_3mf(path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """``{name: (V (nv, 3) float, T (t, 3) int)}`` of every object of a 3MF file (vertices as stored)."""
    import xml.etree.ElementTree as ET

    ns = "{%s}" % CORE
    out = {}
    try:
        with zipfile.ZipFile(path) as z, z.open("3D/3dmodel.model") as fh:
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
