"""``flat.json``: the flat data of every part cut from sheet, and the check that it defines the part.

For every panel and beam (every ply and interlayer of a glass unit, with its
``member`` and ``material``) and every cap plate of a tube hub
(:func:`fabricate.cad.parts.cut_from_sheet`): the outline to cut (mm, in the part frame, as the
DXF draws it before nesting), the bevel reference line with its corner
heights, the bevel angle of every edge on both sides, the sheet thickness
and the 4 x 4 transform that places the part in the model (see
:mod:`fabricate.cad.flat` for the frame).  Per group: the face list, which
face each edge's bevel cuts and the reference corners, so a reader can
rebuild the solid without this package: :func:`check_flat` does that from
the file alone and compares the result with the STEP (or 3MF) solid of the
same id: volume and Hausdorff distance within :data:`TOL_MM`.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from fabricate.cad.parts import cut_from_sheet
from optimize import jsontext
from optimize.atomic import atomic_open
from optimize.errors import ExportError, write_error

TOL_MM = 0.01
"""Largest accepted Hausdorff distance (mm); the volume may differ by this times the outline area."""
FORMAT = "conical-fab flat data 1"


def write_flat(parts, path) -> dict:
    """Write ``flat.json`` (atomic).  Returns facts: ``file, bytes, parts, seconds``."""
    t0 = time.perf_counter()
    path = Path(path)
    groups, n = [], 0
    for g in parts.groups:
        if not cut_from_sheet(g.kind, g.member) or not len(g):
            continue
        groups.append({
            "kind": g.kind, "member": g.member, "material": g.material or ("glass" if g.kind == "panel" else "steel"),
            "faces": [list(f) for f in g.faces], "top_face": g.outline_face,
            "bottom_face": g.bevel_face, "cuts": g.cuts, "reference_corners": list(g.ring),
            "ids": list(g.ids), "thickness_mm": g.thickness_mm, "outline": g.flat,
            "bevel_reference": g.bevel_ref, "bevel_reference_z_mm": g.bevel_ref_z,
            "bevel_deg": g.bevel_deg, "transform": g.transform, "rect_mm": g.rect})
        n += len(g)
    doc = {"format": FORMAT, "units": "mm", "frame": (
        "part frame: the sheet lies between z = -thickness and z = 0 (the reference face: panel bearing "
        "face, beam + plate face, hub cap: its lower face) seen from +z; outline counter-clockwise; transform maps part frame to "
        "model; bevel_deg[j] = [+z side, -z side] of edge j -> j+1, degrees from square, positive when "
        "the part narrows toward that face; cut face of edge j side s passes through the bevel reference "
        "edge j at its corner heights"), "groups": groups}
    try:
        with atomic_open(path, "w", encoding="utf-8") as fh:
            for text in _json_chunks(doc):
                fh.write(text)
    except OSError as exc:
        raise write_error(path, "flat data", exc) from exc
    return {"file": path.name, "bytes": path.stat().st_size, "parts": n, "seconds": time.perf_counter() - t0}


def _json_chunks(doc):
    """The text of ``json.dumps(doc, separators=(",", ":"))``, a group at a time (``doc["groups"]``
    its last key), with the numpy arrays of the groups (which ``json`` cannot take) as their
    ``tolist()``: see :func:`json_array`."""
    head = "".join(f"{_dumps(k)}:{_dumps(v)}," for k, v in doc.items() if k != "groups")
    yield "{" + head + '"groups":['
    for j, g in enumerate(doc["groups"]):
        yield ("," if j else "") + "{" + ",".join(
            f"{_dumps(k)}:{json_array(v) if isinstance(v, np.ndarray) else _dumps(v)}" for k, v in g.items()) + "}"
    yield "]}"


def _dumps(value) -> str:
    return json.dumps(value, separators=(",", ":"))


def json_array(a: np.ndarray) -> str:
    """``json.dumps(a.tolist(), separators=(",", ":"))``, the same text, faster for a float or int array
    of any shape: the numbers as ``repr`` writes them (as ``json`` does a finite float or an int), each
    distinct value once (told apart by its bits: ``-0.0`` is not ``0.0``), put in a template of the
    brackets, without the nested lists.  Other arrays, or any NaN or infinity (``NaN``, ``Infinity``
    in JSON): ``json`` itself."""
    if a.size == 0 or a.dtype.kind not in "fiu" or (a.dtype.kind == "f" and not np.isfinite(a).all()):
        return _dumps(a.tolist())
    template = "%s"
    for n in reversed(a.shape):
        template = "[" + ",".join([template] * n) + "]"
    flat = np.ascontiguousarray(a).ravel()
    bits, back = np.unique(flat.view(f"u{flat.itemsize}"), return_inverse=True)
    words = np.array(list(map(repr, bits.view(flat.dtype).tolist())), dtype=object)
    return template % tuple(words[back].tolist())


def read_flat(path) -> list[dict]:
    """The groups of a ``flat.json`` with their arrays as numpy arrays; a file that does not have
    the layout :func:`write_flat` writes (a missing key, an array of the wrong shape, a face or a
    corner index out of range) is refused with an :class:`ExportError` naming the group and the key."""
    try:
        with open(path, encoding="utf-8") as fh:
            doc = jsontext.loads(fh.read())
    except (OSError, ValueError) as exc:
        raise ExportError(f"{path}: not a readable flat data file ({exc})") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        got = doc.get("format") if isinstance(doc, dict) else type(doc).__name__
        raise ExportError(f"{path}: format {got!r}, expected {FORMAT!r}")
    groups = doc.get("groups")
    if not isinstance(groups, list):
        raise ExportError(f"{path}: key 'groups' is {type(groups).__name__}, expected a list of part groups")
    return [_group(g, j, path) for j, g in enumerate(groups)]


_SHAPES = {"thickness_mm": (), "outline": ("k", 2), "bevel_reference": ("k", 2), "bevel_reference_z_mm": ("k",),
           "bevel_deg": ("k", 2), "transform": (4, 4), "rect_mm": (2,)}
"""The per-part arrays of a group: their shape after the part axis (``k``: the outline's corners)."""


def _group(g, j: int, path) -> dict:
    """Group ``j`` of a flat.json, checked and with numpy arrays (see :func:`read_flat`)."""
    def bad(key, value, expected):
        text = repr(value)
        raise ExportError(f"{path}: group {j + 1} key {key!r}: {text[:60] + '...' if len(text) > 60 else text}; "
                          f"expected {expected}")

    if not isinstance(g, dict):
        bad("groups", g, "an object of part arrays")
    g = dict(g)
    for key in ("kind", "member", "material"):
        if not isinstance(g.get(key), str):
            bad(key, g.get(key), "a string")
    ids = g.get("ids")
    if not isinstance(ids, list) or not all(isinstance(i, str) for i in ids):
        bad("ids", ids, "a list of part ids (strings)")
    faces = g.get("faces")
    if (not isinstance(faces, list) or len(faces) < 4
            or not all(isinstance(f, list) and len(f) >= 3 and all(type(v) is int and v >= 0 for v in f)
                       for f in faces)):
        bad("faces", faces, "a list of at least 4 faces, each a list of 3 or more vertex indices")
    g["faces"] = tuple(tuple(f) for f in faces)
    nv = 1 + max(max(f) for f in faces)
    on = np.zeros(nv, np.int64)
    for f in faces:
        on[list(set(f))] += 1
    if (on < 3).any():
        bad("faces", faces, f"every vertex on 3 faces or more (vertex {int(np.argmax(on < 3))} is not)")
    for key in ("top_face", "bottom_face"):
        if type(g.get(key)) is not int or not 0 <= g[key] < len(faces):
            bad(key, g.get(key), f"a face index 0..{len(faces) - 1}")
    ring = g.get("reference_corners")
    if not isinstance(ring, list) or len(ring) < 3 or not all(type(v) is int and 0 <= v < nv for v in ring):
        bad("reference_corners", ring, f"a list of 3 or more vertex indices 0..{nv - 1}")
    k = len(ring)
    try:
        cuts = np.asarray(g.get("cuts"), dtype=np.int64)
    except (TypeError, ValueError, OverflowError):
        cuts = None
    if cuts is None or cuts.shape != (k, 2) or (cuts < 0).any() or (cuts >= len(faces)).any():
        bad("cuts", g.get("cuts"), f"{k} pairs of face indices 0..{len(faces) - 1} (one per outline edge)")
    g["cuts"] = cuts
    p = len(ids)
    for key, tail in _SHAPES.items():
        shape = (p,) + tuple(k if d == "k" else d for d in tail)
        try:
            a = np.asarray(g.get(key), dtype=float)
        except (TypeError, ValueError, OverflowError):
            a = None
        if a is None or a.shape != shape:
            bad(key, g.get(key), f"numbers of shape {shape} ({p} parts, {k} outline corners)")
        g[key] = a
    return g


def rebuild(g: dict) -> np.ndarray:
    """(p, nv, 3): the corners of every solid of a flat.json group, rebuilt from its flat data (mm)."""
    from fabricate.cad.flat import corner_triples, face_planes, solid_from_flat

    N, O = face_planes(g["bevel_reference"], g["bevel_reference_z_mm"], g["bevel_deg"], g["thickness_mm"],
                       g["cuts"], len(g["faces"]), g["top_face"], g["bottom_face"], g["transform"])
    return solid_from_flat(N, O, corner_triples(g["faces"], N), g["reference_corners"], g["bevel_reference"],
                           g["bevel_reference_z_mm"], g["transform"])


def solid_corners(shape) -> np.ndarray:
    """(m, 3) distinct vertex points of an OpenCASCADE shape, or of a solid as the STEP text reader
    gives it (a dict whose ``faces`` are (k, 3) loops)."""
    if isinstance(shape, dict):
        return np.unique(np.concatenate([np.asarray(f, dtype=float) for f in shape["faces"]]), axis=0)
    from OCP.BRep import BRep_Tool
    from OCP.TopAbs import TopAbs_VERTEX
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    pts = []
    ex = TopExp_Explorer(shape, TopAbs_VERTEX)
    while ex.More():
        p = BRep_Tool.Pnt_s(TopoDS.Vertex(ex.Current()))
        pts.append((p.X(), p.Y(), p.Z()))
        ex.Next()
    return np.unique(np.array(pts, dtype=float), axis=0)


def check_flat(path, bom: list[dict], step_solids: dict | None = None, meshes: dict | None = None) -> dict:
    """The flat data against the solids: every part of the BOM cut from sheet (panels, beams, hub caps:
    :func:`~fabricate.cad.parts.cut_from_sheet`) is in ``flat.json``; the
    solid rebuilt from its outline, bevels, thickness and transform has the solid's volume (the BOM's
    analytic one, which the STEP and 3MF checks hold to their files) and its corners are within
    :data:`TOL_MM` of the STEP solid's (``step_solids``: name -> OCC shape) or else the 3MF mesh's
    (``meshes``: name -> object with ``V``) corners: a Hausdorff bound of the two polyhedra.
    The volume tolerance is :data:`TOL_MM` times the part's outline area (a 0.01 mm skin)."""
    from fabricate.cad.geometry import volumes

    groups = read_flat(path)
    expected = {r["id"]: r for r in bom if cut_from_sheet(r["kind"], r.get("member", ""))}
    against = "step" if step_solids else "3mf" if meshes else None
    seen, failures = set(), []
    worst_h, worst_v, worst_id = 0.0, 0.0, None
    for g in groups:
        X = rebuild(g)
        vol = volumes(X, g["faces"])
        hd = _hausdorff_all(X, _corner_sets(g["ids"], expected, against, step_solids, meshes))
        ids = g["ids"]
        seen.update(ids)
        rows = [expected.get(pid) for pid in ids]
        known = np.array([r is not None for r in rows], dtype=bool)
        ref = np.array([(float(r["volume_mm3"]), float(r["area_m2"])) if r is not None else (0.0, 0.0)
                        for r in rows]).reshape(-1, 2)
        dv = np.abs(vol - ref[:, 0])                                        # (p,)
        has_h = np.array([h is not None for h in hd], dtype=bool)
        H = np.array([np.nan if h is None else h for h in hd], dtype=float)
        with np.errstate(invalid="ignore"):
            bad = (~(dv <= TOL_MM * (ref[:, 1] * 1e6)) | (has_h & ~(H <= TOL_MM))   # NaN: no figure, a failure
                   | (~has_h & bool(against)))
            hv = np.where(known & has_h & ~np.isnan(H), H, -np.inf)
        if len(ids) and known.any():
            j = int(np.argmax(hv))                                          # the first of the largest
            if hv[j] > worst_h:
                worst_h, worst_id = hd[j], ids[j]
            dk = dv[known]
            dk = dk[~np.isnan(dk)]
            if len(dk) and dk.max() > worst_v:
                worst_v = dk[int(np.argmax(dk))]
        for i in np.flatnonzero(~known | bad).tolist():                    # the failures, in order
            if rows[i] is None:
                failures.append({"id": ids[i], "error": "no BOM row of that id"})
            else:
                failures.append({"id": ids[i], "volume_error_mm3": dv[i], "hausdorff_mm": hd[i]})
    missing = sorted(set(expected) - seen)
    ok = not missing and not failures
    return {"pass": ok, "parts": len(seen), "expected": len(expected), "missing": missing[:20],
            "against": against or "bom volumes only", "hausdorff_mm_max": worst_h, "worst": worst_id,
            "volume_error_mm3_max": worst_v, "tolerance_mm": TOL_MM, "failures": failures[:20],
            "failed": len(failures),
            "how": "each solid rebuilt from flat.json alone (outline, bevels, thickness, transform); "
                   "Hausdorff bound = largest distance between the two corner sets"}


def _step_points(shape) -> np.ndarray:
    """(m, 3) the corners of a STEP solid: the text reader's face loops one after the other (a corner
    once per face), an OpenCASCADE shape's distinct vertices."""
    if isinstance(shape, dict):
        return np.concatenate([np.asarray(f, dtype=float) for f in shape["faces"]])
    return solid_corners(shape)


class _Stacked(list):
    """``corners`` for :func:`_hausdorff_all` (a list: ``None`` or ``(m_i, 3)`` per part) that also
    carries them stacked by ``m``: ``buckets = [(rows (c,), B (c, m, 3))]``, so no part's array is cut
    out and stacked again."""
    buckets: list


def _corner_sets(ids, expected: dict, against, step_solids, meshes) -> list:
    """The file's corners of every part of a group (``None``: not compared): the STEP solid's face
    loops (:func:`_step_points`) or the 3MF mesh's vertices.  Solids of the text reader (which keep
    the file's loop array, ``loops``) are gathered for the whole group at once, the same points in
    the same order."""
    n = len(ids)
    if against == "3mf":
        return [np.asarray(meshes[p].V, dtype=float) if p in expected and p in meshes else None for p in ids]
    if against != "step":
        return [None] * n
    rows = [i for i, p in enumerate(ids) if p in expected and p in step_solids]
    shapes = [step_solids[ids[i]] for i in rows]
    loops = [getattr(s, "loops", None) for s in shapes]
    P0, F0, C0 = loops[0][:3] if rows and loops[0] is not None else (None, None, None)
    shared = P0 is not None and all(lp is not None and lp[0] is P0 and lp[1] is F0 and lp[2] is C0
                                    for lp in loops)
    faces = [lp[3] for lp in loops] if shared else []                     # (f_i,) loop indices
    nf = np.array([len(f) for f in faces], dtype=np.int64)
    if not shared or not nf.all():                  # other solids, or one without faces: one at a time
        out = [None] * n
        for i, s in zip(rows, shapes):
            out[i] = _step_points(s)
        return out
    P, first, counts = P0, F0, C0
    F = np.concatenate(faces).astype(np.int64)
    cn = np.asarray(counts)[F].astype(np.int64)
    st = np.asarray(first)[F].astype(np.int64)
    ends = np.cumsum(cn)
    index = np.repeat(st - (ends - cn), cn) + np.arange(int(ends[-1]) if len(ends) else 0)   # loops, in order
    m = np.add.reduceat(cn, np.concatenate([[0], np.cumsum(nf)[:-1]]))
    off = np.concatenate([[0], np.cumsum(m)[:-1]])
    out = _Stacked([None] * n)
    out.buckets = []
    rows_a = np.asarray(rows, dtype=np.int64)
    for k in np.unique(m).tolist():
        sel = np.flatnonzero(m == k)
        B = np.asarray(P, dtype=float)[index[off[sel][:, None] + np.arange(k)]]      # (c, k, 3)
        out.buckets.append((rows_a[sel], B))
        for r, Bi in zip(rows_a[sel].tolist(), B):
            out[r] = Bi
    return out


def _hausdorff_all(X: np.ndarray, corners: list[np.ndarray | None]) -> list[float | None]:
    """:func:`_hausdorff` of every ``X[i] (nv, 3)`` and ``corners[i] (m_i, 3)`` (None: no figure), the
    parts with the same ``m`` at once (chunks of about :data:`HAUSDORFF_CHUNK` x 8 x 24 distances).

    The same figures as :func:`_hausdorff` to the last digit: a point repeated in every part of a
    bucket (a corner in each face loop) is taken once, the squared distances are summed as
    ``np.linalg.norm`` sums them, and the square root (monotonic, correctly rounded) is taken of the
    extreme only."""
    out: list[float | None] = [None] * len(corners)
    buckets = getattr(corners, "buckets", None)
    if buckets is None:
        by_m: dict[int, list[int]] = {}
        for i, B in enumerate(corners):
            if B is not None:
                by_m.setdefault(len(B), []).append(i)
        buckets = [(np.array(ix), np.stack([corners[i] for i in ix])) for ix in by_m.values()]
    for ix, B in buckets:
        B = B[:, _distinct_columns(B)]
        chunk = max(1, HAUSDORFF_CHUNK * 8 * 24 // max(1, X.shape[1] * B.shape[1]))
        for lo in range(0, len(ix), chunk):
            part = ix[lo:lo + chunk]
            A, Bc = X[part], B[lo:lo + chunk]
            D = _squared_distances(A, Bc)                                     # (c, nv, m)
            h = np.sqrt(np.maximum(D.min(axis=2).max(axis=1), D.min(axis=1).max(axis=1)))
            for i, v in zip(part.tolist(), h.tolist()):
                out[i] = v
    return out


def _squared_distances(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``(c, nv, m)`` squared distances of ``A (c, nv, 3)`` and ``B (c, m, 3)``, summed x, y, z in this
    order (as ``((A - B) ** 2).sum(axis=-1)`` and ``np.linalg.norm`` sum them), a coordinate at a time."""
    D = np.empty((A.shape[0], A.shape[1], B.shape[1]))
    t = np.empty_like(D)
    for j in range(3):
        np.subtract(A[:, :, None, j], B[:, None, :, j], out=t)
        np.multiply(t, t, out=t)
        if j:
            D += t
        else:
            D, t = t, D
    return D


def _distinct_columns(B: np.ndarray) -> np.ndarray:
    """Indices of the columns of ``B (c, m, 3)`` left when a column equal in every part to an earlier
    one is dropped (the distances to it are the same figures); all of them when the first part's
    repeats are not repeats in every part (or there are NaNs)."""
    if not len(B) or not B.shape[1]:
        return np.arange(B.shape[1])
    _, first, rep = np.unique(B[0], axis=0, return_index=True, return_inverse=True)
    rep = first[np.asarray(rep).ravel()]
    if len(first) == B.shape[1] or not (B == B[:, rep]).all():
        return np.arange(B.shape[1])
    return np.sort(first)


HAUSDORFF_CHUNK = 2000


def _hausdorff(A: np.ndarray, B: np.ndarray) -> float:
    D = np.linalg.norm(A[:, None, :] - B[None, :, :], axis=2)
    return float(max(D.min(axis=1).max(), D.min(axis=0).max()))
