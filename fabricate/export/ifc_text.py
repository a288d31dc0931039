"""The per-part entities of the IFC4 file as ISO 10303-21 text (:func:`fabricate.export.ifc.write_ifc`).

The file's skeleton (project, site, building, curtain wall, units, contexts,
materials) is made by ifcopenshell; everything per part is written here as
text, continuing the skeleton's entity ids:

1. every solid of every group, group by group (the ids of a group's solids
   by offset: solid ``i`` of a group of ``nf`` faces starts at ``base + i *
   (nf + 2)``): its ``IfcCartesianPointList3D`` (the part's own vertices in
   mm, numbers formatted in bulk), one ``IfcIndexedPolygonalFace`` (or
   ``...WithVoids``) per face (the group's face list is one template) and
   its ``IfcPolygonalFaceSet``;
2. per unit (:class:`Unit`): its body representation (none for an
   ``IfcElementAssembly``), placement and element, its quantity set and property
   set with their ``IfcRelDefinesByProperties``; an assembly's parts follow it
   (placed relative to it) and its ``IfcRelAggregates``;
3. the curtain wall's ``IfcRelAggregates`` of every top-level element (glass
   units, assemblies, one-solid members) and one ``IfcRelAssociatesMaterial``
   per material (the glass layer set, the steel, each profile set).

Strings are escaped as ifcopenshell writes them (``'`` doubled, ``\\``
doubled, anything but printable ASCII as ``\\X2\\....\\X0\\`` or
``\\X4\\........\\X0\\``); reals are Python's shortest round-trip ``repr``
with the ``.`` Part 21 asks for (``1.E-05``); GlobalIds are random UUIDs
(version 4) in IFC's 22-character base 64, encoded in bulk.
"""
from __future__ import annotations

import base64
import os
import re
from dataclasses import dataclass, field

import numpy as np

CHUNK = 2000  # solids or units formatted per write
_STD = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/"
_IFC = "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz_$"
_TO_IFC = str.maketrans(_STD, _IFC)
_LISTS = str.maketrans({"[": "(", "]": ")", " ": None, "e": "E"})
_NO_DOT = re.compile(r"([^\d.]\d)e")  # repr's one-digit mantissa without '.' (1e-05): Part 21 wants 1.E-05
QUANTITY = {"length": "IFCQUANTITYLENGTH", "area": "IFCQUANTITYAREA", "volume": "IFCQUANTITYVOLUME",
            "weight": "IFCQUANTITYWEIGHT"}


def new_guids(n: int) -> list[str]:
    """``n`` GlobalIds: random version-4 UUIDs (as ``uuid.uuid4``), compressed as
    ``ifcopenshell.guid.compress`` does (base 64 of the 128 bits behind 16 zero bits, first 2
    characters dropped, IFC's alphabet), all at once."""
    raw = np.zeros((n, 18), np.uint8)
    raw[:, 2:] = np.frombuffer(os.urandom(16 * n), np.uint8).reshape(n, 16)
    raw[:, 8] = (raw[:, 8] & 0x0F) | 0x40         # version 4
    raw[:, 10] = (raw[:, 10] & 0x3F) | 0x80       # RFC 4122 variant
    text = base64.b64encode(raw.tobytes()).decode("ascii").translate(_TO_IFC)  # 18 bytes: 24 characters
    return [text[k + 2:k + 24] for k in range(0, 24 * n, 24)]


def string(s: str) -> str:
    """A Part 21 string literal (quotes included), escaped as ifcopenshell escapes it."""
    if s.isascii() and s.isprintable():
        return "'" + s.replace("\\", "\\\\").replace("'", "''") + "'"
    out, run = [], []

    def flush():
        if run:
            wide = any(ord(c) > 0xFFFF for c in run)
            out.append(("\\X4\\" if wide else "\\X2\\")
                       + "".join(f"{ord(c):0{8 if wide else 4}X}" for c in run) + "\\X0\\")
            run.clear()
    for c in s:
        if " " <= c <= "~":
            flush()
            out.append("\\\\" if c == "\\" else "''" if c == "'" else c)
        else:
            run.append(c)
    flush()
    return "'" + "".join(out) + "'"


def real(x) -> str:
    """A Part 21 real that reads back as exactly ``float(x)``: ``repr`` with a ``.`` and ``E``."""
    r = repr(float(x))
    if "e" in r:
        m, e = r.split("e")
        r = m + ("" if "." in m else ".") + "E" + e
    return r[:-1] if r.endswith(".0") else r                # 1. as ifcopenshell writes it


def point_lists(V: np.ndarray) -> list[str]:
    """``((x,y,z),...)`` of each part of ``V (p, nv, 3)``: exact reals, formatted in one pass."""
    text = "\x00".join(map(repr, V.tolist()))
    if "e" in text:
        text = _NO_DOT.sub(r"\1.e", text)
    return text.replace(".0,", ".,").replace(".0]", ".]").translate(_LISTS).split("\x00")


def _face(face) -> str:
    def idx(loop):
        return "(" + ",".join(str(int(i) + 1) for i in loop) + ")"
    if isinstance(face[0], tuple):  # the outer loop, then each hole
        return f"IFCINDEXEDPOLYGONALFACEWITHVOIDS({idx(face[0])},(" + ",".join(idx(h) for h in face[1:]) + "));\n"
    return f"IFCINDEXEDPOLYGONALFACE({idx(face)});\n"


class SolidText:
    """The Part 21 template of one group's solids: ``nf + 2`` entities each, ids from ``base``."""

    def __init__(self, faces, n: int, base: int):
        self.nf, self.n, self.base = len(faces), n, base
        self.stride = self.nf + 2
        rows = [f"#%d={_face(f)}" for f in faces]
        self.template = ("#%d=IFCCARTESIANPOINTLIST3D(%s);\n" + "".join(rows)
                         + "#%d=IFCPOLYGONALFACESET(#%d,.T.,(" + ",".join(["#%d"] * self.nf) + "),$);\n")

    def face_set(self, i: int) -> int:
        """The id of the ``IfcPolygonalFaceSet`` of solid ``i``."""
        return self.base + i * self.stride + self.nf + 1

    def write(self, fh, V: np.ndarray) -> None:
        offs = np.arange(self.stride)
        for lo in range(0, self.n, CHUNK):
            hi = min(lo + CHUNK, self.n)
            ids = (self.base + np.arange(lo, hi)[:, None] * self.stride + offs).tolist()
            out = []
            for row, pts in zip(ids, point_lists(V[lo:hi])):
                out.append(self.template % (row[0], pts, *row[1:], row[0], *row[1:-1]))
            fh.write("".join(out))


@dataclass
class Unit:
    """One element: ``kind`` (panel, beam, node), its IFC class, predefined and object type, its id,
    description, solids ``[(group index, part index)]`` (none: an element without a body of its own, an
    assembly), quantity set (name, ``{key: (kind, value)}``), fabrication property set (``{key: str | int |
    float}``), ``material``: the key in ``refs`` of what it is made of (``layers``, ``steel``, a profile
    set), and ``parts``: the units an ``IfcElementAssembly`` aggregates (placed relative to it)."""
    kind: str
    cls: str
    predefined: str
    object_type: str | None
    uid: str
    description: str
    solids: list
    qto_name: str
    quantities: dict
    props: dict
    material: str = "steel"
    parts: list = field(default_factory=list)

    def count(self) -> int:
        """Elements this unit writes: itself and its parts."""
        return 1 + sum(p.count() for p in self.parts)


def _value(v) -> str:
    if isinstance(v, str):
        return ("IFCLABEL(" if len(v) <= 255 else "IFCTEXT(") + string(v) + ")"
    if isinstance(v, (int, np.integer)):
        return f"IFCINTEGER({int(v)})"
    return f"IFCREAL({real(v)})"


def _defined_by(out: list, nid: int, el: int, guids, cls: str, name: str, blanks: str, members: list[str]) -> int:
    """Append ``members`` (entity texts) from id ``nid`` on, the set of class ``cls`` and ``name`` that
    holds them (``blanks``: its unset attributes between the name and the members) and the
    ``IfcRelDefinesByProperties`` tying it to element ``el``; returns the next free id."""
    out.extend(f"#{nid + k}={text};\n" for k, text in enumerate(members))
    s = nid + len(members)
    out.append(f"#{s}={cls}('{next(guids)}',$,{string(name)},{blanks}("
               + ",".join(f"#{k}" for k in range(nid, s)) + "));\n"
               f"#{s + 1}=IFCRELDEFINESBYPROPERTIES('{next(guids)}',$,$,$,(#{el}),#{s});\n")
    return s + 2


ASSEMBLY = "IFCELEMENTASSEMBLY"


def _element(out: list, nid: int, u: Unit, parent_place: int, solids, refs: dict, guids, pset: str,
             materials: dict) -> tuple[int, int]:
    """Append unit ``u`` from id ``nid`` on (placed relative to ``parent_place``): its body (when it has
    solids), placement and element, quantity and property sets, then its parts (placed relative to it) and
    the ``IfcRelAggregates`` that holds them.  Records the element under ``materials[u.material]``.
    Returns ``(element id, next free id)``."""
    name = string(u.uid)
    ot = "$" if u.object_type is None else string(u.object_type)
    if u.solids:
        items = ",".join(f"#{solids[gi].face_set(i)}" for gi, i in u.solids)
        out.append(f"#{nid}=IFCSHAPEREPRESENTATION(#{refs['body']},'Body','Tessellation',({items}));\n"
                   f"#{nid + 1}=IFCLOCALPLACEMENT(#{parent_place},#{refs['origin']});\n"
                   f"#{nid + 2}=IFCPRODUCTDEFINITIONSHAPE($,$,(#{nid}));\n")
        place, shape, el = nid + 1, f"#{nid + 2}", nid + 3
    else:
        out.append(f"#{nid}=IFCLOCALPLACEMENT(#{parent_place},#{refs['origin']});\n")
        place, shape, el = nid, "$", nid + 1
    where = ",.FACTORY." if u.cls == ASSEMBLY else ""   # IfcElementAssembly's AssemblyPlace: welded in the shop
    out.append(f"#{el}={u.cls}('{next(guids)}',$,{name},{string(u.description)},{ot},#{place},"
               f"{shape},{name}{where},.{u.predefined}.);\n")
    materials.setdefault(u.material, []).append(el)
    nid = _defined_by(out, el + 1, el, guids, "IFCELEMENTQUANTITY", u.qto_name, "$,$,",
                      [f"{QUANTITY[kind]}({string(key)},$,$,{real(v)},$)" for key, (kind, v) in u.quantities.items()])
    nid = _defined_by(out, nid, el, guids, "IFCPROPERTYSET", pset, "$,",
                      [f"IFCPROPERTYSINGLEVALUE({string(key)},$,{_value(v)},$)" for key, v in u.props.items()])
    kids = []
    for p in u.parts:
        k, nid = _element(out, nid, p, place, solids, refs, guids, pset, materials)
        kids.append(k)
    if kids:
        out.append(f"#{nid}=IFCRELAGGREGATES('{next(guids)}',$,$,$,#{el},(" + ",".join(f"#{k}" for k in kids) + "));\n")
        nid += 1
    return el, nid


def write_body(fh, groups, faces, units: list[Unit], refs: dict, first_id: int, pset: str) -> int:
    """Write every solid of ``groups`` (faces of each: ``faces``), then every unit (an assembly with its
    parts), then the wall's relations, as Part 21 entities from id ``first_id`` on.  ``refs``: ids of the
    skeleton's ``body`` subcontext, ``origin`` placement, ``wall`` and its placement ``wall_place``, and
    of every material a unit names (``layers``, ``steel``, profile sets).  Returns the next free id."""
    nid = first_id
    solids = []
    for g, fc in zip(groups, faces):
        solids.append(SolidText(fc, len(g), nid))
        nid += len(g) * solids[-1].stride
    for g, t in zip(groups, solids):
        t.write(fh, g.vertices)
    n = sum(u.count() for u in units)
    guids = iter(new_guids(6 * n + 2 + len(refs)))
    materials: dict[str, list[int]] = {}
    top: list[int] = []
    out: list[str] = []
    for u in units:
        el, nid = _element(out, nid, u, refs["wall_place"], solids, refs, guids, pset, materials)
        top.append(el)
        if len(out) > 20 * CHUNK:
            fh.write("".join(out))
            out.clear()
    fh.write("".join(out))

    def refs_of(ids):
        return "(" + ",".join(f"#{i}" for i in ids) + ")"
    tail = []
    if top:  # IfcRelAggregates needs one part at least (ifcopenshell wrote an empty set)
        tail.append(f"#{nid}=IFCRELAGGREGATES('{next(guids)}',$,$,$,#{refs['wall']},{refs_of(top)});\n")
        nid += 1
    for key, ids in materials.items():
        tail.append(f"#{nid}=IFCRELASSOCIATESMATERIAL('{next(guids)}',$,$,$,{refs_of(ids)},#{refs[key]});\n")
        nid += 1
    fh.write("".join(tail))
    return nid
