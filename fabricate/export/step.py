"""STEP (AP214 or AP242, ISO 10303-21) of every part: one assembly, parts named by id, coloured by kind, mm.

Two engines write the same model:

- ``direct`` (default): the Part 21 text is generated from the part
  polygons with one format template per part type (all beams share one
  template, all quad panels another), so 15,000 solids take seconds.  Each
  solid is a ``MANIFOLD_SOLID_BREP`` of ``ADVANCED_FACE`` s on ``PLANE`` s
  with straight ``EDGE_CURVE`` s shared by their two faces, without p-curves
  (valid for planar faces: readers compute them); the entity layout follows
  what OpenCASCADE's own writer produces (product, shape definition, next
  assembly usage occurrence, styled item per solid).
- ``occ``: the solids are built with OpenCASCADE (:mod:`.brep`) and written
  by ``STEPCAFControl_Writer`` through an XCAF document (p-curves omitted
  above ``pcurve_limit`` parts); slower, kept as the reference the direct
  writer is tested against.

``fabricate check`` reads the file back with OpenCASCADE whichever engine
wrote it (BRepCheck, volumes, names).
"""
from __future__ import annotations

import datetime as _dt
import re
import time
from pathlib import Path

import numpy as np

from optimize.atomic import atomic_open
from optimize.errors import ExportError, write_error

from ..cad.parts import COLOURS, KINDS
from .brep import edge_table
from .meshes import require_finite

REAL = "%#.15G"
PREFIX, NAME, INDEX = "\x00", "\x01", "\x02"  # stand-ins in a template: a part's id prefix, its name, its index
CHUNK = 2000  # parts formatted per write


class _Template:
    """The Part 21 text of one solid, as a ``%`` template over its real numbers.

    The ids of a part are a prefix ``P`` followed by ``digits`` digits: entity ``k`` (``0 <= k <
    count``, then the ``N_PRODUCT`` product entities) of the ``j``-th part of a prefix (``j <
    per_prefix``, as many as fit in ``10**digits`` ids) is ``P * 10**digits + j * stride + k``.
    :meth:`text` ``j`` writes every id as ``PREFIX`` and its last ``digits`` digits, so that one
    ``str.replace`` per part writes all its ids (formatting each id as a number took more than
    half of the writer's time), and the ids stay as dense as numbered one by one.  Real
    numbers come from the part's points, edge directions and face normals (a face's plane has no
    reference direction, ``$``: readers take one perpendicular to its normal).  ``fill`` gathers
    them for every part in one fancy-index operation.

    faces : ``(nf,)`` loops of vertex indices, or, for a face with holes, a tuple of loops (the
    outer one counter-clockwise about the outward normal, each hole clockwise);
    normal_of : ``(nf,)`` the row of the group's normals that holds each face's normal (default
    ``0..nf-1``).  V : ``(p, nv, 3)`` the group's vertices: edges parallel in every part (a tube's
    rings and its sides) share one ``DIRECTION`` and ``VECTOR`` (:func:`parallel_edges`); N : ``(p, nf', 3)``
    its face normals: faces with the same or the opposite normal in every part (a plate's two faces)
    share one ``DIRECTION``, an opposite face with ``same_sense`` ``.F.``.
    """

    def __init__(self, faces: tuple, nv: int, normal_of: tuple[int, ...] | None = None,
                 V: np.ndarray | None = None, N: np.ndarray | None = None):
        faces = tuple(f if isinstance(f[0], tuple) else (f,) for f in faces)   # every face: its loops
        loops = [loop for f in faces for loop in f]
        E, per_loop = edge_table(tuple(loops))
        same = np.arange(len(E)) if V is None else parallel_edges(E, V)
        owners = int(np.count_nonzero(same == np.arange(len(E))))
        self.normal_of = np.arange(len(faces)) if normal_of is None else np.asarray(normal_of, dtype=np.int64)
        f_same, f_sign = np.arange(len(faces)), np.ones(len(faces))
        if N is not None:                    # faces parallel in every part share their plane's normal
            f_same, f_sign = parallel_rows(N[:, self.normal_of], opposite=True)
        n_owners = int(np.count_nonzero(f_same == np.arange(len(faces))))
        self.edges = E
        self.faces = faces
        self.nv, self.ne, self.nf = nv, len(E), len(faces)
        lines: list[str] = []
        fields: list[int] = []          # column of the source matrix for every field
        nid = [0]
        # source columns: [local ids (count)] [points 3 nv] [dirs 3 ne] [normals 3 nf]
        counts = 2 * nv + 2 * self.ne + 2 * owners + sum(len(f) for f in loops) + 2 * len(loops) + 3 * self.nf + n_owners + 1
        self.count = counts
        c_pt, c_dir = counts, counts + 3 * nv
        c_nrm = c_dir + 3 * self.ne

        def new(text: str, cols: list[int]) -> int:
            i = nid[0]
            nid[0] += 1
            lines.append("#%d=" + text + ";\n")
            fields.extend([i] + cols)
            return i

        def xyz(c):
            return [c, c + 1, c + 2]
        pt = [new(f"CARTESIAN_POINT('',({REAL},{REAL},{REAL}))", xyz(c_pt + 3 * v)) for v in range(nv)]
        vp = [new("VERTEX_POINT('',#%d)", [pt[v]]) for v in range(nv)]
        ec, vecs = [], {}
        for j, (a, b) in enumerate(E.tolist()):
            if same[j] == j:
                d = new(f"DIRECTION('',({REAL},{REAL},{REAL}))", xyz(c_dir + 3 * j))
                vecs[j] = new("VECTOR('',#%d,1.)", [d])
            line = new("LINE('',#%d,#%d)", [pt[a], vecs[int(same[j])]])
            ec.append(new("EDGE_CURVE('',#%d,#%d,#%d,.T.)", [vp[a], vp[b], line]))
        face_ids, nrms = [], {}
        rows = iter(per_loop)
        for fi, face in enumerate(faces):
            bounds = []
            for li in range(len(face)):
                oe = [new("ORIENTED_EDGE('',*,*,#%d," + (".T.)" if fwd else ".F.)"), [ec[e]]) for e, fwd in next(rows)]
                loop = new("EDGE_LOOP('',(" + ",".join(["#%d"] * len(oe)) + "))", oe)
                bounds.append(new(("FACE_BOUND" if li else "FACE_OUTER_BOUND") + "('',#%d,.T.)", [loop]))
            if f_same[fi] == fi:
                nrms[fi] = new(f"DIRECTION('',({REAL},{REAL},{REAL}))", xyz(c_nrm + 3 * fi))
            ax = new("AXIS2_PLACEMENT_3D('',#%d,#%d,$)", [pt[face[0][0]], nrms[int(f_same[fi])]])
            pl = new("PLANE('',#%d)", [ax])
            sense = ".T." if f_sign[fi] > 0 else ".F."              # .F.: the face's normal is the plane's reversed
            face_ids.append(new("ADVANCED_FACE('',(" + ",".join(["#%d"] * len(bounds)) + "),#%d," + sense + ")",
                                bounds + [pl]))
        self.shell = new("CLOSED_SHELL('',(" + ",".join(["#%d"] * len(face_ids)) + "))", face_ids)
        assert nid[0] == counts
        self.stride = counts + N_PRODUCT
        self.digits = len(str(self.stride - 1))
        self.per_prefix = 10 ** self.digits // self.stride
        pieces = re.split(r"(%d|%#\.15G)", "".join(lines))
        self._pieces = pieces[0::2]
        self._locals = [col if spec == "%d" else None for spec, col in zip(pieces[1::2], fields)]
        self.fields = np.asarray([c - counts for c in fields if c >= counts], dtype=np.int64)
        assert len(self.fields) == self._locals.count(None)

    def _local(self, j: int, k: int) -> str:
        return f"{PREFIX}{j * self.stride + k:0{self.digits}d}"

    def text(self, j: int) -> str:
        """The geometry of the ``j``-th part of a prefix: a ``%`` template over its reals (:meth:`fill`)."""
        out = [self._pieces[0]]
        for col, lit in zip(self._locals, self._pieces[1:]):
            out.append(REAL if col is None else self._local(j, col))
            out.append(lit)
        return "".join(out)

    def fill(self, V: np.ndarray, N: np.ndarray) -> np.ndarray:
        """(p, nreals) float: the real numbers of every part, in text order."""
        p = len(V)
        a, b = self.edges[:, 0], self.edges[:, 1]
        D = V[:, b] - V[:, a]
        D /= np.linalg.norm(D, axis=2, keepdims=True)
        src = np.concatenate([V.reshape(p, -1), D.reshape(p, -1), N[:, self.normal_of].reshape(p, -1)], axis=1)
        return src[:, self.fields]

    def product(self, j: int, style: int) -> str:
        """The text of the ``N_PRODUCT`` product-structure entities of the ``j``-th part of a prefix (ids as
        in :meth:`text`; the part's name ``NAME`` and its index in the assembly ``INDEX`` to be filled in)."""
        return _product([self._local(j, self.count + k) for k in range(N_PRODUCT)], self._local(j, self.shell),
                        NAME, INDEX, style)

    def ids(self, first: int, n: int) -> np.ndarray:
        """``(n,)`` the id of entity 0 of each of ``n`` parts from prefix ``first`` on."""
        i = np.arange(n)
        return (first + i // self.per_prefix) * 10 ** self.digits + (i % self.per_prefix) * self.stride


SCHEMAS = {
    "AP214": ("AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }",
              "#1=APPLICATION_CONTEXT('core data for automotive mechanical design processes');\n"
              "#2=APPLICATION_PROTOCOL_DEFINITION('international standard','automotive_design',2000,#1);\n"),
    "AP242": ("AP242_MANAGED_MODEL_BASED_3D_ENGINEERING_MIM_LF { 1 0 10303 442 1 1 4 }",
              "#1=APPLICATION_CONTEXT('managed model based 3d engineering');\n"
              "#2=APPLICATION_PROTOCOL_DEFINITION('international standard',"
              "'ap242_managed_model_based_3d_engineering',2011,#1);\n"),
}
"""``outputs.step_schema``: file schema and application protocol of each; the entities written are
common to both (AP242 took over AP214's product structure, B-rep and presentation entities)."""

GLOBAL = """#3=PRODUCT_CONTEXT('',#1,'mechanical');
#4=PRODUCT_DEFINITION_CONTEXT('part definition',#1,'design');
#5=(LENGTH_UNIT()NAMED_UNIT(*)SI_UNIT(.MILLI.,.METRE.));
#6=(NAMED_UNIT(*)PLANE_ANGLE_UNIT()SI_UNIT($,.RADIAN.));
#7=(NAMED_UNIT(*)SI_UNIT($,.STERADIAN.)SOLID_ANGLE_UNIT());
#8=UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-07),#5,'distance_accuracy_value','confusion accuracy');
#9=(GEOMETRIC_REPRESENTATION_CONTEXT(3)GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#8))GLOBAL_UNIT_ASSIGNED_CONTEXT((#5,#6,#7))REPRESENTATION_CONTEXT('Context #1','3D Context with UNIT and UNCERTAINTY'));
#10=CARTESIAN_POINT('',(0.,0.,0.));
#11=DIRECTION('',(0.,0.,1.));
#12=DIRECTION('',(1.,0.,0.));
#13=AXIS2_PLACEMENT_3D('',#10,#11,#12);
#14=PRODUCT('{name}','{name}','',(#3));
#15=PRODUCT_DEFINITION_FORMATION('','',#14);
#16=PRODUCT_DEFINITION('design','',#15,#4);
#17=PRODUCT_DEFINITION_SHAPE('','',#16);
#18=SHAPE_DEFINITION_REPRESENTATION(#17,#19);
#19=SHAPE_REPRESENTATION('{name}',(#13{placements}),#9);
#20=PRODUCT_RELATED_PRODUCT_CATEGORY('assembly',$,(#14));
"""
N_GLOBAL = 20
STYLE = """#{0}=COLOUR_RGB('{kind}',{r:.6f},{g:.6f},{b:.6f});
#{1}=FILL_AREA_STYLE_COLOUR('',#{0});
#{2}=FILL_AREA_STYLE('',(#{1}));
#{3}=SURFACE_STYLE_FILL_AREA(#{2});
#{4}=SURFACE_SIDE_STYLE('',(#{3}));
#{5}=SURFACE_STYLE_USAGE(.BOTH.,#{4});
#{6}=PRESENTATION_STYLE_ASSIGNMENT((#{5}));
"""
N_PRODUCT = 15  # entities per part after the geometry (see _product)


def _product(i: list[str], shell: str, name: str, index: str, style: int) -> str:
    """Text of the 15 product-structure entities of one part (ids ``i[0] .. i[14]``, its shell ``shell``)."""
    return (f"#{i[0]}=MANIFOLD_SOLID_BREP('{name}',#{shell});\n"
            f"#{i[1]}=ADVANCED_BREP_SHAPE_REPRESENTATION('{name}',(#13,#{i[0]}),#9);\n"
            f"#{i[2]}=PRODUCT('{name}','{name}','',(#3));\n"
            f"#{i[3]}=PRODUCT_DEFINITION_FORMATION('','',#{i[2]});\n"
            f"#{i[4]}=PRODUCT_DEFINITION('design','',#{i[3]},#4);\n"
            f"#{i[5]}=PRODUCT_DEFINITION_SHAPE('','',#{i[4]});\n"
            f"#{i[6]}=SHAPE_DEFINITION_REPRESENTATION(#{i[5]},#{i[1]});\n"
            f"#{i[7]}=PRODUCT_RELATED_PRODUCT_CATEGORY('part',$,(#{i[2]}));\n"
            f"#{i[8]}=NEXT_ASSEMBLY_USAGE_OCCURRENCE('{index}','{name}','',#16,#{i[4]},$);\n"
            f"#{i[9]}=PRODUCT_DEFINITION_SHAPE('Placement','Placement of an item',#{i[8]});\n"
            f"#{i[10]}=AXIS2_PLACEMENT_3D('',#10,#11,#12);\n"
            f"#{i[11]}=ITEM_DEFINED_TRANSFORMATION('','',#13,#{i[10]});\n"
            f"#{i[12]}=(REPRESENTATION_RELATIONSHIP('','',#{i[1]},#19)"
            f"REPRESENTATION_RELATIONSHIP_WITH_TRANSFORMATION(#{i[11]})SHAPE_REPRESENTATION_RELATIONSHIP());\n"
            f"#{i[13]}=CONTEXT_DEPENDENT_SHAPE_REPRESENTATION(#{i[12]},#{i[9]});\n"
            f"#{i[14]}=STYLED_ITEM('color',(#{style}),#{i[0]});\n")


def write_step(parts, path, *, engine: str = "direct", name: str = "model", pcurve_limit: int = 500,
               schema: str = "AP214") -> dict:
    """Write every part of ``parts`` to one STEP file (atomic).

    engine : ``direct`` (fast text writer) or ``occ`` (OpenCASCADE XCAF writer).
    name : name of the top assembly.  pcurve_limit : ``occ`` only: models with
    more parts are written without p-curves (about half the file).
    schema : ``AP214`` (automotive design, read by every CAD program) or ``AP242`` (managed
    model-based 3D engineering, its successor).
    Returns facts: ``file, bytes, parts, entities, schema, engine, pcurves, seconds``.
    Raises ExportError when the file cannot be written.
    """
    t0 = time.perf_counter()
    path = Path(path)
    if schema not in SCHEMAS:
        raise ExportError(f"{path.name}: STEP schema {schema!r}: expected one of {', '.join(SCHEMAS)}")
    require_finite(parts)
    if engine == "occ":
        from .step_occ import write_step_occ

        facts = write_step_occ(parts, path, name=name, pcurves=len(parts) <= pcurve_limit, schema=schema)
    elif engine == "direct":
        facts = _write_direct(parts, path, name, schema)
    else:
        raise ExportError(f"{path.name}: STEP engine {engine!r}: expected 'direct' or 'occ'")
    facts.update(file=path.name, bytes=path.stat().st_size, parts=len(parts), engine=engine,
                 schema=f"{schema} ({SCHEMAS[schema][0].split()[0]})", units="mm", seconds=time.perf_counter() - t0)
    return facts


def _write_direct(parts, path: Path, name: str, schema: str = "AP214") -> dict:
    groups = [g for g in parts.groups if len(g)]
    templates = [_Template(faces, g.vertices.shape[1], normal_of, g.vertices, g.normals)
                 for g in groups for faces, normal_of in [step_faces(g)]]
    style_base = {kind: N_GLOBAL + 1 + 7 * i for i, kind in enumerate(KINDS)}
    next_id = N_GLOBAL + 1 + 7 * len(KINDS)
    n_entities = next_id
    prefixes, bases = [], []   # the ids of each group's parts follow the last group's, increasing through the file
    for g, t in zip(groups, templates):
        slot = 10 ** t.digits
        first = -(-next_id // slot)
        prefixes.append(first + np.arange(len(g)) // t.per_prefix)
        bases.append(t.ids(first, len(g)))
        next_id = (int(prefixes[-1][-1]) + 1) * slot
        n_entities += len(g) * t.stride
    placements = np.concatenate([b + t.count + 10 for b, t in zip(bases, templates)]) if groups else []
    styled = np.concatenate([b + t.count + 14 for b, t in zip(bases, templates)]) if groups else []
    stamp = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%S")
    counts = ", ".join(f"{sum(len(g) for g in parts.of_kind(k))} {k}s" for k in KINDS)
    try:
        with atomic_open(path, "w", encoding="ascii", newline="\n") as fh:
            fh.write("ISO-10303-21;\nHEADER;\n"
                     f"FILE_DESCRIPTION(('conical-fab model: {counts}; ids P=panel B=beam N=node; mm'),'2;1');\n"
                     f"FILE_NAME('{path.name}','{stamp}',(''),(''),'conical-fab','conical-fab','');\n"
                     f"FILE_SCHEMA(('{SCHEMAS[schema][0]}'));\nENDSEC;\nDATA;\n")
            fh.write(SCHEMAS[schema][1] + GLOBAL.replace("{name}", _safe(name)).replace(
                "{placements}", "".join(f",#{int(i)}" for i in placements)))
            for kind in KINDS:
                s = style_base[kind]
                r, g_, b = COLOURS[kind]
                fh.write(STYLE.format(*range(s, s + 7), kind=kind, r=r, g=g_, b=b))
            index = 0
            for g, t, pre in zip(groups, templates, prefixes):
                m = t.per_prefix
                texts = [t.text(j) for j in range(min(m, len(g)))]
                products = [t.product(j, style_base[g.kind] + 6) for j in range(len(texts))]
                for lo in range(0, len(g), CHUNK):  # chunks bound the memory of the text
                    hi = min(lo + CHUNK, len(g))
                    vals = t.fill(g.vertices[lo:hi], g.normals[lo:hi])
                    out = []
                    for i, row, p, pid in zip(range(lo, hi), vals.tolist(), pre[lo:hi].tolist(), g.ids[lo:hi]):
                        index += 1
                        j = i % m
                        out.append((texts[j] % tuple(row) + products[j].replace(NAME, pid).replace(INDEX, str(index)))
                                   .replace(PREFIX, str(p)))
                    fh.write("".join(out))
            fh.write(f"#{next_id}=MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION('',("
                     + ",".join(f"#{int(i)}" for i in styled) + "),#9);\nENDSEC;\nEND-ISO-10303-21;\n")
    except OSError as exc:
        raise write_error(path, "STEP file", exc) from exc
    return {"entities": int(n_entities), "pcurves": False}


PARALLEL = 1e-12
"""Edges whose unit directions differ by at most this (every coordinate, in every part of a group) share one."""


def parallel_edges(E: np.ndarray, V: np.ndarray) -> np.ndarray:
    """``(ne,)`` for each edge ``E (ne, 2)`` the first edge parallel to it (same direction within
    :data:`PARALLEL`) in every part ``V (p, nv, 3)``, itself when there is none."""
    D = V[:, E[:, 1]] - V[:, E[:, 0]]
    D /= np.maximum(np.linalg.norm(D, axis=2, keepdims=True), 1e-300)
    return parallel_rows(D)[0]


def parallel_rows(D: np.ndarray, opposite: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """``(same (n,), sign (n,))``: for each unit vector ``D[:, i]`` (``D (p, n, 3)``) the first one equal
    to it in every part within :data:`PARALLEL` (itself when there is none), or, with ``opposite``,
    equal or opposite (``sign`` -1: opposite)."""
    n = D.shape[1]
    signs = (1.0, -1.0) if opposite else (1.0,)
    close = np.zeros((len(signs), n, n), bool)
    for k, sg in enumerate(signs):                                                    # in the first part
        close[k] = np.abs(D[0][:, None, :] - sg * D[0][None, :, :]).max(axis=2) <= PARALLEL
    any_close = close.any(axis=0)
    same = np.argmax(any_close, axis=1)
    sign = np.where(close[0][np.arange(n), same], 1.0, -1.0)
    while not np.array_equal(same[same], same):                                       # to the first of each set
        sign, same = sign * sign[same], same[same]
    ok = np.abs(D - sign[None, :, None] * D[:, same]).max(axis=(0, 2)) <= PARALLEL    # in every part
    return np.where(ok, same, np.arange(n)), np.where(ok, sign, 1.0)


def step_faces(group) -> tuple[tuple, tuple[int, ...] | None]:
    """``(faces, normal_of)`` of a group's solids in STEP (:class:`_Template`): its polygons, except
    a hub tube's, whose ends are written as one annulus each, a face with a hole
    (:func:`fabricate.cad.hubs.tube_step_faces`), as OpenCASCADE's writer does."""
    if group.kind == "node" and group.member == "tube":
        from fabricate.cad.hubs import tube_step_faces

        return tube_step_faces(group.vertices.shape[1] // 4)
    return group.faces, None


def _safe(text: str) -> str:
    """A STEP string literal body: printable ASCII, quotes doubled."""
    return "".join(c if 32 <= ord(c) < 127 else "_" for c in text).replace("'", "''")
