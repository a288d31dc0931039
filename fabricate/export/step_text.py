"""An independent reader of planar STEP B-reps (ISO 10303-21 text), for checking files fast.

``read_step_text(path)`` parses the entities a planar-faced ``MANIFOLD_SOLID_BREP``
is made of (points, vertices, lines, edge curves, oriented edges, loops,
bounds, planes, faces, closed shells) with one regular expression per entity
type over the whole file, into numpy arrays, follows each solid to its part
name (product -> definition -> shape representation) and its colour (styled
item -> ... -> ``COLOUR_RGB``), and measures every solid from the file alone:

- ``closed``: every edge curve of the shell is used by exactly two of its face
  loops, once in each direction (a closed, consistently oriented 2-manifold);
- ``euler``: ``V - E + F`` of the shell (2 for one solid without holes);
- ``loops_closed``: each loop's edges join end to start;
- ``on_plane`` / ``on_line``: the largest distance of a loop vertex from its
  face's ``PLANE`` and of an edge's end points from its ``LINE`` (mm);
- ``normals_agree``: each loop turns counter-clockwise about its face's
  outward normal (the plane's axis, with the face's ``same_sense`` and the
  bound's orientation);
- ``simple``: each face loop turns once (total turning +-360 degrees);
- ``volume_mm3``: divergence theorem over the loops (positive: outward).

It never uses the writer (:mod:`fabricate.export.step`) nor OpenCASCADE, so
it is an independent reading of what the file says.  It reads what a planar
B-rep writer produces (AP203/AP214 entity names, one or more entities per
line, whitespace between tokens allowed); a file with other geometry (curved
surfaces, inner bounds) is reported as unsupported, not guessed at.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from optimize.errors import ExportError

_S = rb"\s*"
_STR = rb"'(?:[^']|'')*'"
_REFS = rb"(#\d+(?:\s*,\s*#\d+)*)"          # a fixed run of references, parsed at once
_LIST = rb"\(\s*(#\d+(?:\s*,\s*#\d+)*)\s*\)"  # a list of references
_NUMS = rb"\(([^()]*)\)"                    # a list of numbers
_BOOL = rb"\.([TF])\."


def _rx(kind: bytes, *args: bytes) -> re.Pattern:
    """A pattern that starts with the literal ``=KIND(`` (found fast), its arguments as groups."""
    body = (_S + rb"," + _S).join(args)
    return re.compile(rb"=" + kind + rb"\(" + _S + body + _S + rb"\)" + _S + rb";")


RX = {
    "point": _rx(b"CARTESIAN_POINT", _STR, _NUMS),
    "direction": _rx(b"DIRECTION", _STR, _NUMS),
    "vertex": _rx(b"VERTEX_POINT", _STR, _REFS),
    "vector": _rx(b"VECTOR", _STR, _REFS, rb"[-+0-9.EeDd]+"),
    "line": _rx(b"LINE", _STR, _REFS),
    "edge": _rx(b"EDGE_CURVE", _STR, _REFS, _BOOL),
    "oriented": _rx(b"ORIENTED_EDGE", _STR, rb"\*", rb"\*", _REFS, _BOOL),
    "loop": _rx(b"EDGE_LOOP", _STR, _LIST),
    "bound": _rx(b"FACE_OUTER_BOUND", _STR, _REFS, _BOOL),
    "axis": _rx(b"AXIS2_PLACEMENT_3D", _STR, _REFS, rb"(?:#\d+|\$)"),
    "plane": _rx(b"PLANE", _STR, _REFS),
    "face": _rx(b"ADVANCED_FACE", _STR, _LIST, _REFS, _BOOL),
    "shell": _rx(b"CLOSED_SHELL", _STR, _LIST),
    "solid": _rx(b"MANIFOLD_SOLID_BREP", rb"'((?:[^']|'')*)'", _REFS),
}
SMALL = {  # few entities (a few per part): their groups are read in Python
    "product": _rx(b"PRODUCT", rb"'((?:[^']|'')*)'", rb"[^;]*?"),
    "formation": _rx(b"PRODUCT_DEFINITION_FORMATION", _STR, _STR, rb"#(\d+)"),
    "definition": _rx(b"PRODUCT_DEFINITION", _STR, _STR, rb"#(\d+)", rb"#\d+"),
    "pds": _rx(b"PRODUCT_DEFINITION_SHAPE", _STR, _STR, rb"#(\d+)"),
    "sdr": _rx(b"SHAPE_DEFINITION_REPRESENTATION", rb"#(\d+)", rb"#(\d+)"),
    "rep": _rx(b"ADVANCED_BREP_SHAPE_REPRESENTATION", _STR, rb"\(([^()]*)\)", rb"#\d+"),
    "styled": _rx(b"STYLED_ITEM", _STR, rb"\(([^()]*)\)", rb"#(\d+)"),
    "psa": _rx(b"PRESENTATION_STYLE_ASSIGNMENT", rb"\(([^()]*)\)"),
    "ssu": _rx(b"SURFACE_STYLE_USAGE", rb"\.\w+\.", rb"#(\d+)"),
    "sss": _rx(b"SURFACE_SIDE_STYLE", _STR, rb"\(([^()]*)\)"),
    "ssfa": _rx(b"SURFACE_STYLE_FILL_AREA", rb"#(\d+)"),
    "fas": _rx(b"FILL_AREA_STYLE", _STR, rb"\(([^()]*)\)"),
    "fasc": _rx(b"FILL_AREA_STYLE_COLOUR", _STR, rb"#(\d+)"),
    "rgb": _rx(b"COLOUR_RGB", _STR, rb"([-+0-9.EeDd]+)", rb"([-+0-9.EeDd]+)", rb"([-+0-9.EeDd]+)"),
}
UNSUPPORTED = (b"B_SPLINE", b"CYLINDRICAL_SURFACE", b"CONICAL_SURFACE", b"SPHERICAL_SURFACE",
               b"TOROIDAL_SURFACE", b"=CIRCLE(", b"=ELLIPSE(", b"=FACE_BOUND(", b"=FACE_SURFACE(")


def _refs(text: bytes) -> list[int]:
    return [int(x) for x in re.findall(rb"#(\d+)", text)]


def _numbers(parts: list[bytes], what: str, path, ints: bool = False) -> np.ndarray:
    """All numbers (or ``#`` references) of ``parts`` joined, parsed in C (``np.fromstring``)."""
    text = b",".join(parts)
    if ints:
        text = text.replace(b"#", b"")
    else:
        text = text.replace(b"D", b"E").replace(b"d", b"e")
    if not text.strip():
        return np.zeros(0, dtype=np.int64 if ints else np.float64)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        A = np.fromstring(text, dtype=np.float64, sep=",")
    expected = text.count(b",") + 1
    if A.size != expected or not np.all(np.isfinite(A)):
        raise ExportError(f"{path}: a {what} has an item that is not a number")
    return A.astype(np.int64) if ints else A


def _by_kind(data: bytes) -> dict[bytes, bytes]:
    """The DATA section's records grouped by entity name: ``{b"CARTESIAN_POINT": b"#1=...;\\n#7=...;"}``,
    so that each kind's pattern runs over its own records only."""
    from operator import itemgetter

    a, b = data.find(b"DATA;"), data.rfind(b"ENDSEC;")
    body = data[a + 5:b].replace(b"\r", b"").strip()
    recs = body.split(b";\n")
    split = body.count(b"\n") < len(recs)
    if not split:  # records broken over lines, or several on one line
        recs = [b" ".join(x.split()) for x in re.split(rb";\s*(?=#\d+\s*=)", body)]
    recs[-1] = recs[-1].rstrip().rstrip(b";")
    joined = b";\n" + (body if split else b";\n".join(recs))
    names = re.findall(rb";\n#\d+\s*=\s*([A-Z0-9_]*)", joined)
    del joined
    if len(names) != len(recs):
        names = [r[r.find(b"=") + 1:r.find(b"(")].strip() for r in recs]
    code: dict[bytes, int] = {}
    kinds = np.array([code.setdefault(n, len(code)) for n in names])
    order = np.argsort(kinds, kind="stable")
    bounds = np.concatenate([[0], np.cumsum(np.bincount(kinds, minlength=len(code)))])
    out = {}
    for name, c in code.items():
        idx = order[bounds[c]:bounds[c + 1]].tolist()
        got = itemgetter(*idx)(recs) if len(idx) > 1 else (recs[idx[0]],)
        out[name.replace(b" ", b"")] = b";\n".join(got) + b";\n"
    return out


class _Kind:
    """Entities of one kind: ``ids (r,)``, their captured groups, a dense id -> row lookup."""

    def __init__(self, text: bytes, rx: re.Pattern, path):
        found = re.compile(rb"#(\d+)\s*" + rx.pattern).findall(text)
        if found and not isinstance(found[0], tuple):
            found = [(x,) for x in found]
        self.ids = np.array([int(g[0]) for g in found], dtype=np.int64)
        self.groups = [g[1:] for g in found]
        if len(found) != text.count(b";\n"):
            kind = rx.pattern[1:rx.pattern.index(b"\\(")].decode()
            raise ExportError(f"{path}: {text.count(b';' + bytes([10])) - len(found)} {kind} entities do not "
                              "have the arguments a planar B-rep writer gives them")
        self.row = None

    def column(self, i: int) -> list[bytes]:
        return [g[i] for g in self.groups]

    def lookup(self, row: np.ndarray, kind: np.ndarray, code: int) -> None:
        """Share the file's id -> row and id -> kind arrays; this kind is ``code``."""
        self.row, self.kind, self.code = row, kind, code

    def at(self, refs, what: str, path) -> np.ndarray:
        refs = np.asarray(refs, dtype=np.int64)
        i = np.clip(refs, 0, len(self.row) - 1)
        r = self.row[i]
        bad = (self.kind[i] != self.code) | (refs >= len(self.row)) | (refs < 0)
        if bad.any():
            raise ExportError(f"{path}: #{int(refs[np.argmax(bad)])} is not a {what}")
        return r


def _segments(lists: list[bytes], path) -> tuple[np.ndarray, np.ndarray]:
    """Flat refs and offsets ``(L+1,)`` of a column of ``#a,#b,...`` lists."""
    counts = np.fromiter((x.count(b"#") for x in lists), dtype=np.int64, count=len(lists))
    flat = _numbers(lists, "list of references", path, ints=True)
    if flat.size != counts.sum():
        raise ExportError(f"{path}: a list of references has an item that is not a #reference")
    return flat, np.concatenate([[0], np.cumsum(counts)])


def read_step_text(path) -> tuple[dict[str, dict], dict]:
    """``({part name: facts}, file facts)`` of every solid in a planar STEP file.

    Facts per solid: ``faces`` (list of ``(k, 3)`` loops, counter-clockwise
    about the outward normal), ``volume_mm3``, ``closed``, ``euler``,
    ``loops_closed``, ``normals_agree``, ``simple``, ``on_plane_mm``,
    ``on_line_mm``, ``colour`` (sRGB 0..1 or None), ``valid`` (all of them).
    File facts: ``unit_mm``, ``complete``, ``uncertainty_mm``, ``solids``,
    ``unnamed``, ``in_assembly``.  Raises ExportError when the file is not a
    STEP file this reader understands.
    """
    path = Path(path)
    data = path.read_bytes()
    if not data.lstrip().startswith(b"ISO-10303-21;"):
        raise ExportError(f"{path}: not a STEP file (no ISO-10303-21; header)")
    for word in UNSUPPORTED:
        if word in data:
            raise ExportError(f"{path}: has {word.decode().strip('=(')} entities; this check reads planar "
                              "B-reps only (run `fabricate check --occ` to read it with OpenCASCADE)")
    texts = _by_kind(data)
    K = {}
    for k, rx in {**RX, **SMALL}.items():
        text = texts.get(rx.pattern[1:rx.pattern.index(b"\\(")], b"")
        K[k] = _Kind(text, rx, path)
    size = 1 + max((int(k.ids.max()) for k in K.values() if k.ids.size), default=0)
    row = np.full(size, -1, dtype=np.int64)       # one lookup for every kind: ids are unique in a file
    kind = np.full(size, -1, dtype=np.int16)
    for c, k in enumerate(K.values()):
        row[k.ids] = np.arange(len(k.ids))
        kind[k.ids] = c
        k.lookup(row, kind, c)

    def refs(kind: str, col: int, width: int) -> np.ndarray:
        return _numbers(K[kind].column(col), kind, path, ints=True).reshape(-1, width)

    def flag(kind: str, col: int) -> np.ndarray:
        return np.array([x == b"T" for x in K[kind].column(col)], dtype=bool)

    pts = _numbers(K["point"].column(0), "CARTESIAN_POINT", path).reshape(-1, 3)
    dirs = _numbers(K["direction"].column(0), "DIRECTION", path).reshape(-1, 3)
    if len(pts) != len(K["point"].ids) or len(dirs) != len(K["direction"].ids):
        raise ExportError(f"{path}: a CARTESIAN_POINT or DIRECTION without three coordinates")
    vert_pt = K["point"].at(refs("vertex", 0, 1)[:, 0], "CARTESIAN_POINT", path)
    er = refs("edge", 0, 3)
    E = er
    e_v = K["vertex"].at(er[:, :2].ravel(), "VERTEX_POINT", path).reshape(-1, 2)
    e_line = K["line"].at(er[:, 2], "LINE", path)
    lr = refs("line", 0, 2)
    l_pt = K["point"].at(lr[:, 0], "CARTESIAN_POINT", path)
    l_vec = K["vector"].at(lr[:, 1], "VECTOR", path)
    v_dir = K["direction"].at(refs("vector", 0, 1)[:, 0], "DIRECTION", path)
    o_edge = K["edge"].at(refs("oriented", 0, 1)[:, 0], "EDGE_CURVE", path)
    o_fwd = flag("oriented", 1)
    lp_refs, lp_off = _segments(K["loop"].column(0), path)
    lp_oe = K["oriented"].at(lp_refs, "ORIENTED_EDGE", path)
    b_loop = K["loop"].at(refs("bound", 0, 1)[:, 0], "EDGE_LOOP", path)
    b_fwd = flag("bound", 1)
    ar = refs("axis", 0, 2)
    a_pt = K["point"].at(ar[:, 0], "CARTESIAN_POINT", path)
    a_dir = K["direction"].at(ar[:, 1], "DIRECTION", path)
    p_axis = K["axis"].at(refs("plane", 0, 1)[:, 0], "AXIS2_PLACEMENT_3D", path)
    fb_refs, fb_off = _segments(K["face"].column(0), path)
    if np.any(np.diff(fb_off) != 1):
        raise ExportError(f"{path}: a face with inner bounds (holes); this check reads faces with one "
                          "bound only (run `fabricate check --occ`)")
    Fc = K["face"].ids
    f_bound = K["bound"].at(fb_refs, "FACE_OUTER_BOUND", path)
    f_plane = K["plane"].at(refs("face", 1, 1)[:, 0], "PLANE", path)
    f_same = flag("face", 2)
    sh_refs, sh_off = _segments(K["shell"].column(0), path)
    sh_face = K["face"].at(sh_refs, "ADVANCED_FACE", path)
    S = [(int(i), g[0]) for i, g in zip(K["solid"].ids.tolist(), K["solid"].groups)]
    s_shell = K["shell"].at(refs("solid", 1, 1)[:, 0], "CLOSED_SHELL", path)

    # geometry of every face loop: vertices in traversal order (bound orientation applied)
    face_loop = b_loop[f_bound]
    face_fwd = b_fwd[f_bound]
    counts = np.diff(lp_off)[face_loop]                                   # (F,) edges per face
    starts = lp_off[face_loop]
    fidx = np.repeat(np.arange(len(Fc)), counts)
    k = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    rev = ~face_fwd[fidx]
    pos = np.where(rev, counts[fidx] - 1 - k, k)                          # bound .F.: loop reversed
    oe = lp_oe[starts[fidx] + pos]
    fwd = o_fwd[oe] ^ rev                                                 # direction the edge is walked
    edge = o_edge[oe]
    v_from = np.where(fwd, e_v[edge, 0], e_v[edge, 1])
    v_to = np.where(fwd, e_v[edge, 1], e_v[edge, 0])
    first = np.cumsum(counts) - counts
    nxt = np.arange(len(k)) + 1
    nxt[np.cumsum(counts) - 1] = first                                    # wrap around each face
    joined = v_to == v_from[nxt]
    loops_closed = np.logical_and.reduceat(joined, first) if len(first) else np.zeros(0, bool)
    P = pts[vert_pt[v_from]]                                              # (sum k, 3)
    P1 = P[nxt]
    cross = np.cross(P, P1)
    area_vec = 0.5 * np.add.reduceat(cross, first, axis=0)               # (F, 3) Newell
    ax = p_axis[f_plane]
    normal = dirs[a_dir[ax]] * np.where(f_same, 1.0, -1.0)[:, None]
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    origin = pts[a_pt[ax]]
    on_plane = np.abs(np.einsum("ij,ij->i", P - origin[fidx], normal[fidx]))
    agree = np.einsum("ij,ij->i", area_vec, normal) > 0
    d0 = P1 - P
    d1 = d0[nxt]
    turn = np.arctan2(np.einsum("ij,ij->i", np.cross(d0, d1), normal[fidx]), np.einsum("ij,ij->i", d0, d1))
    simple = np.abs(np.abs(np.add.reduceat(turn, first)) - 2 * np.pi) < 1e-6
    vol_face = np.einsum("ij,ij->i", area_vec, origin) / 3.0              # planar face: n.x constant

    # edge points on their lines
    lp = pts[l_pt[e_line]]
    ld = dirs[v_dir[l_vec[e_line]]]
    ld /= np.maximum(np.linalg.norm(ld, axis=1, keepdims=True), 1e-300)
    on_line = np.zeros(len(E))
    for j in (0, 1):
        D = pts[vert_pt[e_v[:, j]]] - lp
        on_line = np.maximum(on_line, np.linalg.norm(D - np.einsum("ij,ij->i", D, ld)[:, None] * ld, axis=1))

    # per solid: faces of its shell, edge uses, Euler characteristic (vectorized over all solids)
    names, colours = _names(K, S), _colours(K)
    n_s = len(S)
    sh_count = np.diff(sh_off)[s_shell]                                   # faces per solid
    s_faces = np.concatenate([sh_face[sh_off[sh]:sh_off[sh + 1]] for sh in s_shell.tolist()]) \
        if n_s else np.zeros(0, np.int64)
    s_first = np.concatenate([[0], np.cumsum(sh_count)])
    face_solid = np.full(len(Fc), -1, dtype=np.int64)
    face_solid[s_faces] = np.repeat(np.arange(n_s), sh_count)
    el_solid = face_solid[fidx]                                           # (sum k,) solid of each edge use
    m = el_solid >= 0
    key = el_solid[m] * len(E) + edge[m]
    uk, inv, uses = np.unique(key, return_inverse=True, return_counts=True)
    signed = np.bincount(inv, weights=np.where(fwd[m], 1.0, -1.0), minlength=len(uk))
    bad_edge = (uses != 2) | (signed != 0)
    closed = np.bincount(uk // len(E), weights=bad_edge, minlength=n_s) == 0
    n_edges = np.bincount(uk // len(E), minlength=n_s)
    vkey = np.unique(el_solid[m] * len(vert_pt) + v_from[m])
    n_verts = np.bincount(vkey // len(vert_pt), minlength=n_s)
    euler = n_verts - n_edges + sh_count

    def per_solid(values, how):
        out = np.zeros(n_s) if how == "max" else np.ones(n_s, dtype=bool)
        sel = face_solid >= 0 if len(values) == len(Fc) else m
        solid = face_solid if len(values) == len(Fc) else el_solid
        if how == "max":
            np.maximum.at(out, solid[sel], values[sel])
        else:
            np.logical_and.at(out, solid[sel], values[sel])
        return out

    lc, ag, sm = (per_solid(x, "all") for x in (loops_closed, agree, simple))
    plane_err = per_solid(on_plane, "max")
    line_err = per_solid(on_line[edge], "max")
    volume = np.bincount(face_solid[face_solid >= 0], weights=vol_face[face_solid >= 0], minlength=n_s)
    out = {}
    for si, (sid, label) in enumerate(S):
        fl = s_faces[s_first[si]:s_first[si + 1]].tolist()
        name = names.get(int(sid)) or label.decode("ascii", "replace")
        out[name] = {
            "faces": [P[first[f]:first[f] + counts[f]] for f in fl],
            "volume_mm3": float(volume[si]), "closed": bool(closed[si]), "euler": int(euler[si]),
            "loops_closed": bool(lc[si]), "normals_agree": bool(ag[si]), "simple": bool(sm[si]),
            "on_plane_mm": float(plane_err[si]), "on_line_mm": float(line_err[si]),
            "colour": colours.get(int(sid)), "named": int(sid) in names}
    unc = re.search(rb"LENGTH_MEASURE\(\s*([-+0-9.EeDd]+)\s*\)\s*,\s*#\d+\s*,\s*'distance_accuracy_value'", data)
    head = data[: 1 << 16].replace(b" ", b"")
    file_facts = {"unit_mm": b"SI_UNIT(.MILLI.,.METRE.)" in head,
                  "complete": data.rstrip().endswith(b"END-ISO-10303-21;"),
                  "uncertainty_mm": float(unc.group(1).replace(b"D", b"E")) if unc else None,
                  "solids": len(S), "unnamed": sum(not f["named"] for f in out.values()),
                  "duplicate_names": len(S) - len(out), "reader": "independent STEP text reader"}
    return out, file_facts


def _small(K, kind: str) -> list[tuple]:
    return [(int(i),) + tuple(g) for i, g in zip(K[kind].ids.tolist(), K[kind].groups)]


def _names(K, S) -> dict[int, str]:
    """solid id -> product name, by product <- formation <- definition <- shape <- shape representation."""
    product = {r[0]: r[1].decode("ascii", "replace").replace("''", "'") for r in _small(K, "product")}
    formation = {r[0]: int(r[1]) for r in _small(K, "formation")}
    definition = {r[0]: int(r[1]) for r in _small(K, "definition")}
    pds = {r[0]: int(r[1]) for r in _small(K, "pds")}
    rep_items = {r[0]: _refs(r[1]) for r in _small(K, "rep")}
    out = {}
    for _, shape, rep in _small(K, "sdr"):
        d = pds.get(int(shape))
        f = definition.get(d) if d is not None else None
        p = formation.get(f) if f is not None else None
        name = product.get(p) if p is not None else None
        if name is None:
            continue
        for item in rep_items.get(int(rep), []):
            out[item] = name
    solids = {sid for sid, _ in S}
    return {k: v for k, v in out.items() if k in solids}


def _colours(K) -> dict[int, tuple]:
    """solid id -> sRGB of its surface style, by styled item -> ... -> COLOUR_RGB."""
    def first(refs_text, table):
        return next((table[i] for i in _refs(refs_text) if table.get(i)), None)

    rgb = {r[0]: tuple(round(float(x.replace(b"D", b"E")), 6) for x in r[1:4]) for r in _small(K, "rgb")}
    fasc = {r[0]: rgb.get(int(r[1])) for r in _small(K, "fasc")}
    fas = {r[0]: first(r[1], fasc) for r in _small(K, "fas")}
    ssfa = {r[0]: fas.get(int(r[1])) for r in _small(K, "ssfa")}
    sss = {r[0]: first(r[1], ssfa) for r in _small(K, "sss")}
    ssu = {r[0]: sss.get(int(r[1])) for r in _small(K, "ssu")}
    psa = {r[0]: first(r[1], ssu) for r in _small(K, "psa")}
    out = {}
    for _, styles, item in _small(K, "styled"):
        c = first(styles, psa)
        if c is not None:
            out[int(item)] = c
    return out
