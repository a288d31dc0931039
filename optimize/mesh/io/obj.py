"""Wavefront OBJ: polygon meshes from ``v`` and ``f`` records.

Read: ``v x y z [w | r g b]`` (the first three numbers are kept), ``f`` with
``v``, ``v/vt``, ``v//vn`` and ``v/vt/vn`` tokens, 1-based or negative
(relative) indices, polygons of any size, ``#`` comments, ``\\`` line
continuations.  Texture coordinates, normals, groups, smoothing, materials,
polylines (``l``) and points (``p``) are ignored; unknown keywords are noted
in :attr:`Mesh.notes`.

Write: ``v`` lines with ``%.17g`` (a round trip is exact), ``f`` lines with
1-based indices, faces in mesh order.
"""
from __future__ import annotations

import numpy as np

from ...errors import MeshError
from .common import Parsed, face_lists, fail, one_line, to_floats, to_ints, where

#: Keywords of the OBJ format that carry nothing a polygon mesh needs.
IGNORED = frozenset("""vt vn vp g o s usemtl mtllib l p cstype deg bmat step curv curv2 surf
parm trim hole scrv sp end con mg bevel c_interp d_interp lod shadow_obj trace_obj maplib
usemap call csh""".split())


def parse_obj(text: str, path: str) -> Parsed:
    """Parse OBJ ``text`` (read from ``path``, used in messages) into a :class:`Parsed`."""
    lines = text.split("\n")
    v_tok: list[str] = []
    v_line: list[int] = []
    f_tok: list[str] = []
    f_size: list[int] = []
    f_line: list[int] = []
    f_defined: list[int] = []  # vertices defined before each face (for relative indices)
    unknown: dict[str, list[int]] = {}
    i, n = 0, len(lines)
    while i < n:  # the tokenizer: one pass over the lines, numbers parsed in bulk below
        lineno = i + 1
        s = lines[i]
        i += 1
        if "#" in s:
            s = s[: s.index("#")]
        while s.rstrip().endswith("\\") and i < n:
            s = s.rstrip()[:-1] + " " + lines[i]
            i += 1
            if "#" in s:
                s = s[: s.index("#")]
        parts = s.split()
        if not parts:
            continue
        key = parts[0]
        if key == "v":
            if len(parts) < 4:
                raise fail(path, lineno, f"vertex record has {len(parts) - 1} number(s), "
                                         "expected 'v x y z'")
            v_tok += parts[1:4]
            v_line.append(lineno)
        elif key == "f" or key == "fo":
            idx = parts[1:]
            if "/" in s:
                idx = [t.split("/", 1)[0] for t in idx]
            f_tok += idx
            f_size.append(len(idx))
            f_line.append(lineno)
            f_defined.append(len(v_line))
        elif key in IGNORED:
            continue
        else:
            unknown.setdefault(key, []).append(lineno)

    sizes = np.asarray(f_size, dtype=np.int64)
    starts = np.cumsum(sizes) - sizes

    def vertex_at(k: int):
        return where(path, v_line[k // 3]), f" (vertex {k // 3 + 1}, coordinate {'xyz'[k % 3]})"

    def face_at(k: int):
        f = int(np.searchsorted(starts, k, side="right")) - 1
        return where(path, f_line[f]), f" (face record {f + 1}, index {k - starts[f] + 1})"

    V = to_floats(v_tok, vertex_at, "a vertex coordinate").reshape(-1, 3)
    raw = to_ints(f_tok, face_at, "a vertex index")
    F = _resolve(raw, sizes, np.asarray(f_defined, dtype=np.int64), face_at)
    notes = [f"{path}: ignored {len(ls)} '{k}' line(s) (unknown OBJ keyword, first on line {ls[0]})"
             for k, ls in unknown.items()]
    return Parsed(V, F, sizes, np.asarray(v_line, dtype=np.int64),
                  np.asarray(f_line, dtype=np.int64), "line", 1, notes)


def _resolve(raw: np.ndarray, sizes: np.ndarray, defined: np.ndarray, face_at) -> np.ndarray:
    """(c,) int: 0-based indices from 1-based or negative OBJ indices ``raw (c,)``."""
    before = np.repeat(defined, sizes)
    out = np.where(raw > 0, raw - 1, before + raw)
    zero = raw == 0
    if zero.any():
        k = int(np.argmax(zero))
        loc, context = face_at(k)
        raise MeshError(f"{loc}: vertex index 0{context}, expected 1..n or a negative "
                        "(relative) index")
    early = (raw < 0) & (out < 0)
    if early.any():
        k = int(np.argmax(early))
        loc, context = face_at(k)
        raise MeshError(f"{loc}: relative index {int(raw[k])}{context} reaches before the first "
                        f"vertex ({int(before[k])} defined so far), expected -1..-{int(before[k])}")
    return out


def format_obj(mesh, comments=()) -> str:
    """OBJ text of ``mesh``: ``%.17g`` vertices, 1-based faces in mesh order; ``comments`` (one-line
    strings) follow the first comment line."""
    head = f"# {mesh.n_vertices} vertices, {mesh.n_faces} faces (written by conical-fab)\n"
    head += "".join(f"# {c}\n" for c in one_line(comments))
    vs = "".join("v %.17g %.17g %.17g\n" % tuple(r) for r in mesh.V.tolist())
    fs = "".join("f " + " ".join(map(str, f)) + "\n" for f in face_lists(mesh, base=1))
    return head + vs + fs
