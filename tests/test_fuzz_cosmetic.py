"""Valid mesh files in the cosmetic variants real exporters write are read, and read the same.

A 4 x 3 grid written as OBJ (plain, ``v//vn``, ``v/vt/vn``, relative indices, groups and
materials), OFF (counts on the header line or below), ASCII PLY (with an extra element) and
ASCII STL (solids named like keywords, upper case), each optionally indented, with empty
lines, CRLF and a UTF-8 BOM: every variant reads to the same vertices and faces (STL: the
same vertices welded, two triangles a quad).  The hostile side is ``test_fuzz_readers.py``.
"""
from __future__ import annotations

import os

import numpy as np
import pytest
from _fuzz_common import FUZZ, TALLY, Case, print_tally
from hypothesis import given
from hypothesis import strategies as st


@pytest.fixture(scope="module", autouse=True)
def _campaign_table():
    yield
    if os.environ.get("FUZZ_EXAMPLES"):  # the campaign's figures (shown with -s)
        print_tally(("mesh",))


def _grid():
    from optimize.modelling import shapes

    return shapes.grid(4, 3, height=lambda x, y: 0.1 * x * y, name="grid")


STL_NAMES = ["loop", "vertex", "facet normal", "endloop", "", "\u540d\u524d roof", "endsolid"]


@st.composite
def cosmetic(draw):
    """(labels, extension, bytes): a valid grid file with cosmetic variations a real exporter makes."""
    g = _grid()
    fmt = draw(st.sampled_from(["obj", "off", "ply-ascii", "stl-ascii"]))
    labels = [f"valid {fmt}"]
    vs = ["%r %r %r" % tuple(v) for v in g.V.tolist()]
    if fmt == "obj":
        style = draw(st.sampled_from(["plain", "v//vn", "v/vt/vn", "relative"]))
        labels.append(f"valid obj faces {style}")
        lines = ["# caf\u00e9 \u00b2", "o grid", "g panels", "s off", "usemtl glass"] + ["v " + v for v in vs]
        for i, f in enumerate(g.faces_list()):
            if style == "relative":
                idx = [str(j - g.n_vertices) for j in f]
            else:
                idx = [str(j + 1) + {"plain": "", "v//vn": "//1", "v/vt/vn": "/1/1"}[style] for j in f]
            lines.append("f " + " ".join(idx))
        ext = "obj"
    elif fmt == "off":
        inline = draw(st.booleans())
        head = [f"OFF {g.n_vertices} {g.n_faces} 0"] if inline else ["OFF", "# comment", f"{g.n_vertices} {g.n_faces} 0"]
        labels.append("valid off counts on the header line" if inline else "valid off counts below")
        lines = head + vs + [f"{len(f)} " + " ".join(map(str, f)) for f in g.faces_list()]
        ext = "off"
    elif fmt == "ply-ascii":
        junk = draw(st.booleans())
        head = ["ply", "format ascii 1.0", "comment \u00e9crit", f"element vertex {g.n_vertices}",
                "property double x", "property double y", "property double z", f"element face {g.n_faces}",
                "property list uchar int vertex_indices"]
        body = vs + [f"{len(f)} " + " ".join(map(str, f)) for f in g.faces_list()]
        if junk:
            head += ["element material 2", "property float shine"]
            body += ["0.5", "1"]
            labels.append("valid ply extra element")
        lines = head + ["end_header"] + body
        ext = "ply"
    else:
        name = draw(st.sampled_from(STL_NAMES))
        upper = draw(st.booleans())
        labels.append(f"valid stl solid named '{name}'")
        lines = [f"solid {name}"]
        for t in g.V[g.triangulate()].tolist():
            lines += ["facet normal 0 0 1", "outer loop"] + ["vertex %r %r %r" % tuple(v) for v in t]
            lines += ["endloop", "endfacet"]
        lines.append(f"endsolid {name}")
        if upper:
            lines = [ln.upper() if not ln.startswith("vertex") else "VERTEX" + ln[6:] for ln in lines]
            labels.append("valid stl upper case")
        ext = "stl"
    if draw(st.booleans()):
        lines = [("\t" if draw(st.booleans()) else "  ") + ln + " " for ln in lines]
        labels.append("valid indented, trailing blanks")
    if draw(st.booleans()) and fmt != "ply-ascii":
        lines = [x for ln in lines for x in (ln, "")]
        labels.append("valid empty lines")
    sep = draw(st.sampled_from(["\n", "\r\n"]))
    labels.append("valid CRLF" if sep == "\r\n" else "valid LF")
    data = (sep.join(lines) + sep).encode()
    if draw(st.booleans()):
        data = b"\xef\xbb\xbf" + data
        labels.append("valid BOM")
    return Case((labels, ext, data))


@FUZZ
@given(case=cosmetic())
def test_valid_files_in_any_cosmetic_variant_read_the_same(tmp_path_factory, case):
    from optimize.mesh.io import read_mesh

    labels, ext, data = case
    path = tmp_path_factory.mktemp("valid") / f"grid.{ext}"
    path.write_bytes(data)
    try:
        mesh = read_mesh(path)
    except Exception as exc:
        for label in labels:
            TALLY[label, "refused"] += 1
        raise AssertionError((labels, str(exc)))
    g = _grid()
    if ext == "stl":  # welded: the same vertices in another order, two triangles per quad
        got, want = mesh.V[np.lexsort(mesh.V.T)], g.V[np.lexsort(g.V.T)]
        ok = np.array_equal(got, want) and mesh.n_faces == 2 * g.n_faces
    else:
        ok = np.array_equal(mesh.V, g.V) and np.array_equal(mesh.F, g.F)
    for label in labels:
        TALLY[label, "mesh" if ok else "misread"] += 1
    assert ok, labels
