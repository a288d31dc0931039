"""An independent reader of planar STEP B-reps (ISO 10303-21 text), for checking files fast.

``read_step_text(path)`` parses the entities a planar-faced ``MANIFOLD_SOLID_BREP``
is made of (points, vertices, lines, edge curves, oriented edges, loops,
bounds, planes, faces, closed shells) with one regular expression per entity
type over the whole file, into numpy arrays, follows each solid to its part
name (product -> definition -> shape representation) and its colour (styled
item -> ... -> ``COLOUR_RGB``), and measures every solid from the file alone:

- ``closed``: every edge curve of the shell is used by exactly two of its face
  loops, once in each direction (a closed, consistently oriented 2-manifold);
- ``euler``: ``V - E + 2F - L`` of the shell (``L`` loops; ``V - E + F`` when no face has a
  hole): 2 for one solid without through holes, 0 for a tube;
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
line, whitespace between tokens allowed); planar faces may have holes (one
``FACE_OUTER_BOUND`` and a ``FACE_BOUND`` per hole, turning the other way:
``normals_agree`` holds each to its side, ``euler`` is the Euler-Poincare
``V - E + 2F - L`` with ``L`` loops).  A file with other geometry (curved
surfaces) is reported as unsupported, not guessed at.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from optimize.errors import ExportError

from .step_tokens import Records, compact

_STR = rb"'(?:[^']|'')*'"


def _rx(kind: bytes, *args: bytes) -> re.Pattern:
    """A pattern that starts with the literal ``=KIND(`` (found fast), its arguments as groups."""
    return re.compile(rb"=" + kind + rb"\(" + rb",".join(args) + rb"\);")


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
BIG = {  # the planar B-rep: kind -> entity name (read with numpy, :mod:`step_tokens`)
    "point": b"CARTESIAN_POINT", "direction": b"DIRECTION", "vertex": b"VERTEX_POINT", "vector": b"VECTOR",
    "line": b"LINE", "edge": b"EDGE_CURVE", "oriented": b"ORIENTED_EDGE", "loop": b"EDGE_LOOP",
    "bound": b"FACE_OUTER_BOUND", "inner": b"FACE_BOUND", "axis": b"AXIS2_PLACEMENT_3D", "plane": b"PLANE",
    "face": b"ADVANCED_FACE",
    "shell": b"CLOSED_SHELL", "solid": b"MANIFOLD_SOLID_BREP"}
UNSUPPORTED = (b"B_SPLINE", b"CYLINDRICAL_SURFACE", b"CONICAL_SURFACE", b"SPHERICAL_SURFACE",
               b"TOROIDAL_SURFACE", b"SURFACE_OF_", b"OFFSET_SURFACE")
UNSUPPORTED_NAMES = (b"CIRCLE", b"ELLIPSE", b"FACE_SURFACE")
MAX_SPARSE = 4           # ids up to 4 x the record count (+ 10^6) are looked up in a dense array


def _refs(text: bytes) -> list[int]:
    return [int(x) for x in re.findall(rb"#(\d+)", text)]


class _Kind:
    """Entities of one of the SMALL kinds: ``ids (r,)``, their captured groups (regular expression)."""

    def __init__(self, text: bytes, rx: re.Pattern, path):
        found = re.compile(rb"#(\d+)" + rx.pattern).findall(text)
        if found and not isinstance(found[0], tuple):
            found = [(x,) for x in found]
        self.ids = np.array([int(g[0]) for g in found], dtype=np.int64)
        self.groups = [g[1:] for g in found]
        if len(found) != text.count(b";\n"):
            kind = rx.pattern[1:rx.pattern.index(b"\\(")].decode()
            raise ExportError(f"{path}: {text.count(b';' + bytes([10])) - len(found)} {kind} entities do not "
                              "have the arguments a planar B-rep writer gives them")


class _Lookup:
    """id -> (kind code, row within its kind) for every entity of the BIG kinds."""

    def __init__(self, ids_by_kind: list[np.ndarray], n_records: int, path):
        ids = np.concatenate(ids_by_kind) if ids_by_kind else np.zeros(0, np.int64)
        codes = np.repeat(np.arange(len(ids_by_kind)), [len(x) for x in ids_by_kind])
        rows = np.concatenate([np.arange(len(x)) for x in ids_by_kind]) if ids_by_kind else ids
        self.path, top = path, int(ids.max()) + 1 if ids.size else 1
        self.dense = top <= MAX_SPARSE * n_records + 10 ** 6
        if self.dense:
            seen = np.bincount(ids, minlength=top) if ids.size else np.zeros(1, np.int64)
            self.row = np.full(top, -1, np.int64)
            self.kind = np.full(top, -1, np.int16)
            self.row[ids], self.kind[ids] = rows, codes
        else:
            order = np.argsort(ids, kind="stable")
            self.sorted, self.row, self.kind = ids[order], rows[order], codes[order].astype(np.int16)
            seen = np.diff(self.sorted) == 0
        if (seen > 1 if self.dense else seen).any():
            dup = int(np.argmax(seen > 1)) if self.dense else int(self.sorted[np.argmax(seen)])
            raise ExportError(f"{path}: entity id #{dup} is used twice")

    def at_either(self, refs, codes: tuple[int, int], what: str) -> tuple[np.ndarray, np.ndarray]:
        """``(rows, is the second kind)`` of ``refs``, each an entity of one of two kinds."""
        refs = np.asarray(refs, dtype=np.int64).ravel()
        if self.dense:
            i = np.clip(refs, 0, len(self.row) - 1)
            kind = np.where(refs >= len(self.row), -1, self.kind[i])
        else:
            i = np.clip(np.searchsorted(self.sorted, refs), 0, max(len(self.sorted) - 1, 0))
            kind = np.where(self.sorted[i] != refs, -1, self.kind[i])
        bad = (kind != codes[0]) & (kind != codes[1])
        if bad.any():
            raise ExportError(f"{self.path}: #{int(refs[np.argmax(bad)])} is not a {what}")
        return self.row[i], kind == codes[1]

    def at(self, refs, code: int, what: str) -> np.ndarray:
        """Rows of ``refs`` in kind ``code``; ExportError when a reference is not such an entity."""
        refs = np.asarray(refs, dtype=np.int64).ravel()
        if self.dense:
            i = np.clip(refs, 0, len(self.row) - 1)
            bad = (self.kind[i] != code) | (refs >= len(self.row))
        else:
            i = np.clip(np.searchsorted(self.sorted, refs), 0, max(len(self.sorted) - 1, 0))
            bad = (self.sorted[i] != refs) | (self.kind[i] != code)
        if bad.any():
            raise ExportError(f"{self.path}: #{int(refs[np.argmax(bad)])} is not a {what}")
        return self.row[i]


def _parse(data: bytes, path):
    """The BIG kinds as arrays and the SMALL kinds as :class:`_Kind`, from the DATA section."""
    a, b = data.find(b"DATA;"), data.rfind(b"ENDSEC;")
    if a < 0 or b < a:
        raise ExportError(f"{path}: no DATA; ... ENDSEC; section")
    a += 5
    while a < b and data[a] in b" \t\r\n":
        a += 1
    while b > a and data[b - 1] in b" \t\r\n":
        b -= 1
    try:
        return _parse_body(data, a, b, path)
    except ExportError:
        body = compact(data[a:b])
        if body == data[a:b]:
            raise
        return _parse_body(body, 0, len(body), path)          # whitespace or comments between tokens


def _parse_body(data: bytes, a: int, b: int, path):
    R = Records(data, a, b, path)
    hit = next((n for n in R.names if n in UNSUPPORTED_NAMES or any(w in n for w in UNSUPPORTED)), None)
    hit = hit or next((w for t in R.complex_text() for w in UNSUPPORTED if w in t), None)
    if hit is not None:
        raise ExportError(f"{path}: has {hit[:40].decode('ascii', 'replace')} entities; this check reads "
                          "planar B-reps only (run `fabricate check --occ` to read it with OpenCASCADE)")
    rows = {k: R.of(name) for k, name in BIG.items()}
    close = {k: R.after_string(r, BIG[k]) for k, r in rows.items()}
    L = _Lookup([R.ids[rows[k]] for k in BIG], len(R.ids), path)
    code = {k: c for c, k in enumerate(BIG)}
    G: dict[str, np.ndarray] = {}

    def at(refs, kind):
        return L.at(refs, code[kind], BIG[kind].decode())

    for k in ("point", "direction"):
        r, c = rows[k], close[k]
        G[k] = R.template(r, c, ",(N))", BIG[k].decode(), per=3)[2]
    n = {k: BIG[k].decode() for k in BIG}
    G["vert_pt"] = at(R.template(rows["vertex"], close["vertex"], ",#)", n["vertex"])[0][0], "point")
    vr, _, _ = R.template(rows["vector"], close["vector"], ",#,N)", n["vector"])
    G["v_dir"] = at(vr[0], "direction")
    lr = R.template(rows["line"], close["line"], ",#,#)", n["line"])[0]
    G["l_pt"], G["l_vec"] = at(lr[0], "point"), at(lr[1], "vector")
    er = R.template(rows["edge"], close["edge"], ",#,#,#,?)", n["edge"])[0]
    G["e_v"] = at(np.stack(er[:2], axis=1), "vertex").reshape(-1, 2)
    G["e_line"] = at(er[2], "line")
    orr, of, _ = R.template(rows["oriented"], close["oriented"], ",*,*,#,?)", n["oriented"])
    G["o_edge"], G["o_fwd"] = at(orr[0], "edge"), of[0]
    lp, G["lp_off"] = R.ref_list(rows["loop"], close["loop"], n["loop"])
    G["lp_oe"] = at(lp, "oriented")
    br, bf, _ = R.template(rows["bound"], close["bound"], ",#,?)", n["bound"])
    ir, if_, _ = R.template(rows["inner"], close["inner"], ",#,?)", n["inner"])
    G["b_loop"] = np.concatenate([at(br[0], "loop"), at(ir[0], "loop")]).astype(np.int64)
    G["b_fwd"] = np.concatenate([bf[0], if_[0]]).astype(bool)
    G["b_outer"] = np.arange(len(G["b_loop"])) < len(br[0])     # FACE_OUTER_BOUND first, then FACE_BOUND
    ar = _axes(R, rows["axis"], close["axis"])
    G["a_pt"], G["a_dir"] = at(ar[:, 0], "point"), at(ar[:, 1], "direction")
    G["p_axis"] = at(R.template(rows["plane"], close["plane"], ",#)", n["plane"])[0][0], "axis")
    _faces(R, rows["face"], close["face"], G, L, code)
    sh, G["sh_off"] = R.ref_list(rows["shell"], close["shell"], n["shell"])
    G["sh_face"] = at(sh, "face")
    sr = rows["solid"]
    G["s_shell"] = at(R.template(sr, close["solid"], ",#)", n["solid"])[0][0], "shell")
    labels = [R.data[int(o) + 1:int(c)].replace(b"''", b"'") for o, c in zip(R.paren[sr] + 1, close["solid"])]
    G["S"] = list(zip(R.ids[sr].tolist(), labels))
    K = {}
    for k, rx in SMALL.items():
        name = rx.pattern[1:rx.pattern.index(b"\\(")]
        K[k] = _Kind(R.texts(R.of(name)), rx, path)
    return G, K


def _faces(R, fr, close, G, L, code) -> None:
    """Faces with one or more bounds (``ADVANCED_FACE('',(#b1,#b2,...),#plane,.T.)``): ``f_plane``,
    ``f_same`` (F,), and their bounds ``f_bounds`` (rows of ``b_loop``) from ``f_off (F + 1,)``."""
    nb = R.ref_hi[fr] - R.ref_lo[fr] - 1                       # bounds of each face
    if len(fr) and nb.min() < 1:
        raise ExportError(f"{R.path}: ADVANCED_FACE #{int(R.ids[fr[np.argmin(nb)]])} has no bound")
    off = np.concatenate([[0], np.cumsum(nb)]).astype(np.int64)
    G["f_plane"], G["f_same"] = np.zeros(len(fr), np.int64), np.zeros(len(fr), bool)
    refs = np.zeros(int(off[-1]), np.int64)
    for k in np.unique(nb).tolist():                           # one template per number of bounds
        sel = np.flatnonzero(nb == k)
        got, flags, _ = R.template(fr[sel], close[sel], ",(" + ",".join("#" * k) + "),#,?)", "ADVANCED_FACE")
        G["f_plane"][sel] = L.at(got[k], code["plane"], "PLANE")
        G["f_same"][sel] = flags[0]
        for j in range(k):
            refs[off[sel] + j] = got[j]
    rows, inner = L.at_either(refs, (code["bound"], code["inner"]), "FACE_OUTER_BOUND or FACE_BOUND")
    G["f_bounds"] = rows + np.where(inner, int(np.count_nonzero(G["b_outer"])), 0)
    G["f_off"], G["n_faces"] = off, np.int64(len(fr))


def _axes(R, rows, close) -> np.ndarray:
    """``(r, 2)`` location and axis of AXIS2_PLACEMENT_3D records (reference direction or ``$``)."""
    three = R.ref_hi[rows] - R.ref_lo[rows] == 3
    out = np.zeros((len(rows), 2), np.int64)
    for sel, pattern in ((three, ",#,#,#)"), (~three, ",#,#,$)")):
        if sel.any():
            out[sel] = np.stack(R.template(rows[sel], close[sel], pattern, "AXIS2_PLACEMENT_3D")[0][:2], axis=1)
    return out


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
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise ExportError(f"{path}: cannot read the STEP file ({exc.strerror or exc})") from None
    if not data.lstrip()[:64].startswith(b"ISO-10303-21;"):
        raise ExportError(f"{path}: not a STEP file (no ISO-10303-21; header)")
    G, K = _parse(data, path)
    pts, dirs, vert_pt, e_v, e_line = G["point"], G["direction"], G["vert_pt"], G["e_v"], G["e_line"]
    l_pt, l_vec, v_dir, o_edge, o_fwd = G["l_pt"], G["l_vec"], G["v_dir"], G["o_edge"], G["o_fwd"]
    lp_oe, lp_off, b_loop, b_fwd = G["lp_oe"], G["lp_off"], G["b_loop"], G["b_fwd"]
    a_pt, a_dir, p_axis, f_plane, f_same = G["a_pt"], G["a_dir"], G["p_axis"], G["f_plane"], G["f_same"]
    sh_face, sh_off, s_shell, S = G["sh_face"], G["sh_off"], G["s_shell"], G["S"]
    Fc = np.arange(int(G["n_faces"]))
    E = e_line

    # geometry of every bound of every face (U uses of a loop): vertices in traversal order (bound
    # orientation applied); a face with holes has its outer bound and one bound per hole
    use_face = np.repeat(Fc, np.diff(G["f_off"]))                         # (U,) face of each bound
    f_bounds = G["f_bounds"]
    face_loop = b_loop[f_bounds]
    face_fwd = b_fwd[f_bounds]
    counts = np.diff(lp_off)[face_loop]                                   # (U,) edges per bound
    starts = lp_off[face_loop]
    uidx = np.repeat(np.arange(len(face_loop)), counts)                   # (sum k,) bound of each edge use
    fidx = use_face[uidx]                                                 # (sum k,) face of each edge use
    k = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    rev = ~face_fwd[uidx]
    pos = np.where(rev, counts[uidx] - 1 - k, k)                          # bound .F.: loop reversed
    oe = lp_oe[starts[uidx] + pos]
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
    area_vec = 0.5 * np.add.reduceat(cross, first, axis=0)               # (U, 3) Newell
    ax = p_axis[f_plane]
    normal = dirs[a_dir[ax]] * np.where(f_same, 1.0, -1.0)[:, None]
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    origin = pts[a_pt[ax]]
    on_plane = np.abs(np.einsum("ij,ij->i", P - origin[fidx], normal[fidx]))
    along = np.einsum("ij,ij->i", area_vec, normal[use_face])            # (U,) signed area about the normal
    outer = _outer_bounds(G["b_outer"][f_bounds], along, use_face, len(Fc))
    agree = np.where(outer, along > 0, along < 0)                         # holes turn the other way
    d0 = P1 - P
    d1 = d0[nxt]
    turn = np.arctan2(np.einsum("ij,ij->i", np.cross(d0, d1), normal[fidx]), np.einsum("ij,ij->i", d0, d1))
    simple = np.abs(np.abs(np.add.reduceat(turn, first)) - 2 * np.pi) < 1e-6
    outer_use = np.zeros(len(Fc), np.int64)
    outer_use[use_face[outer]] = np.flatnonzero(outer)                    # (F,) the outer bound of each face
    vol_face = np.bincount(use_face, weights=np.einsum("ij,ij->i", area_vec, origin[use_face]),
                           minlength=len(Fc)) / 3.0                        # planar face: n.x constant

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
    use_solid = face_solid[use_face]
    n_loops = np.bincount(use_solid[use_solid >= 0], minlength=n_s)
    euler = n_verts - n_edges + 2 * sh_count - n_loops                     # Euler-Poincare: faces with holes

    def per_solid(values, solid, how):
        out = np.zeros(n_s) if how == "max" else np.ones(n_s, dtype=bool)
        sel = solid >= 0
        if how == "max":
            np.maximum.at(out, solid[sel], values[sel])
        else:
            np.logical_and.at(out, solid[sel], values[sel])
        return out

    lc, ag, sm = (per_solid(x, use_solid, "all") for x in (loops_closed, agree, simple))
    plane_err = per_solid(on_plane, el_solid, "max")
    line_err = per_solid(on_line[edge], el_solid, "max")
    volume = np.bincount(face_solid[face_solid >= 0], weights=vol_face[face_solid >= 0], minlength=n_s)
    out = {}
    o_first, o_counts = first[outer_use], counts[outer_use]               # (F,) each face's outer loop
    for si, (sid, label) in enumerate(S):
        name = names.get(int(sid)) or label.decode("ascii", "replace")
        out[name] = _Facts(P, o_first, o_counts, s_faces[s_first[si]:s_first[si + 1]], {
            "volume_mm3": float(volume[si]), "closed": bool(closed[si]), "euler": int(euler[si]),
            "loops_closed": bool(lc[si]), "normals_agree": bool(ag[si]), "simple": bool(sm[si]),
            "on_plane_mm": float(plane_err[si]), "on_line_mm": float(line_err[si]),
            "colour": colours.get(int(sid)), "named": int(sid) in names})
    unc = re.search(rb"LENGTH_MEASURE\(\s*([-+0-9.EeDd]+)\s*\)\s*,\s*#\d+\s*,\s*'distance_accuracy_value'", data)
    head = data[: 1 << 16].replace(b" ", b"")
    file_facts = {"unit_mm": b"SI_UNIT(.MILLI.,.METRE.)" in head,
                  "complete": data[-256:].rstrip().endswith(b"END-ISO-10303-21;"),
                  "uncertainty_mm": float(unc.group(1).replace(b"D", b"E")) if unc else None,
                  "solids": len(S), "unnamed": sum(not f["named"] for f in out.values()),
                  "duplicate_names": len(S) - len(out), "reader": "independent STEP text reader"}
    return out, file_facts


def _outer_bounds(flagged: np.ndarray, along: np.ndarray, use_face: np.ndarray, n_faces: int) -> np.ndarray:
    """``(U,) bool``: the outer bound of each face.  A face's ``FACE_OUTER_BOUND`` when it has one,
    else its bound of largest area about the face normal (a ``FACE_BOUND`` may bound a face alone or
    be its outer loop: ISO 10303-42); a face with two outer bounds keeps both (and fails ``normals_agree``
    unless both turn the right way, which closed solids cannot have)."""
    has = np.bincount(use_face, weights=flagged, minlength=n_faces) > 0
    best = np.full(n_faces, -np.inf)
    np.maximum.at(best, use_face, np.abs(along))
    return np.where(has[use_face], flagged, np.abs(along) == best[use_face])


class _Facts(dict):
    """One solid's facts; its ``faces`` (list of ``(k, 3)`` outer loops, holes left out) are cut from
    the file's loop array when first asked for (most checks never ask).

    ``loops``: ``(P, first, counts, faces)``, the file's loop points ``P``, each loop's first point and
    point count (shared by every solid of the file), and this solid's outer loops (indices into
    them): callers that gather many solids' corners at once read them here."""

    def __init__(self, P, first, counts, faces, facts):
        super().__init__(facts)
        self.loops = (P, first, counts, faces)

    def __missing__(self, key):
        if key != "faces":
            raise KeyError(key)
        P, first, counts, faces = self.loops
        self["faces"] = [P[first[f]:first[f] + counts[f]] for f in faces.tolist()]
        return self["faces"]


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
