"""Regression tests for the hostile inputs of issue 15, one tiny file each in ``tmp_path``.

Cases that once allocated gigabytes run in the capped worker of
:mod:`test_fuzz_readers` (``RLIMIT_AS``, a time limit, a traced-memory bound), so a
regression fails the test instead of exhausting the machine.
"""
from __future__ import annotations

import json
import math
import os
import struct
import subprocess
import sys

import numpy as np
import pytest

from optimize import Mesh
from optimize.modelling import shapes
from optimize.errors import MeshError
from optimize.mesh.io import read_mesh, write_mesh
from optimize.mesh.measures import summary

from test_fuzz_readers import REPO, Worker

HEAD = ("ply\nformat {enc} 1.0\n{extra}element vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n")
QUAD_ASCII = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"
QUAD_BINARY = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], "<f4").tobytes() + struct.pack("<B4i", 4, 0, 1,
                                                                                                  2, 3)
QUAD_OBJ = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"


@pytest.fixture(scope="module")
def capped(tmp_path_factory):
    w = Worker(tmp_path_factory.mktemp("capped"))
    yield w.run
    w.stop()


def _ply(enc: str, extra: str = "", body: bytes | None = None) -> bytes:
    head = HEAD.format(enc=enc, extra=extra).encode()
    if body is None:
        body = QUAD_ASCII.encode() if enc == "ascii" else QUAD_BINARY
    return head + body


# -- bounded memory and time ------------------------------------------------------------------------
@pytest.mark.parametrize("enc", ["ascii", "binary_little_endian"])
def test_element_without_properties_and_a_huge_count_costs_nothing(capped, enc):
    """A few-hundred-byte header once allocated 30 GiB (np.arange over the count)."""
    res = capped("ply", _ply(enc, "element junk 4000000000\n"))
    assert res["outcome"] == "mesh", res
    assert res["peak"] < 8 << 20, res


def test_counts_are_checked_against_the_bytes_present(capped):
    res = capped("ply", _ply("binary_little_endian").replace(b"element face 1", b"element face 100000000"))
    assert res["outcome"] == "mesh_error", res
    assert "element 'face': 100000000 records of at least 1 byte(s)" in res["detail"], res
    assert ":7:" in res["detail"]  # the header line of the count


def test_a_huge_list_length_is_not_allocated(capped):
    """A list count of 2**31 in a 200-byte file (the 687-byte / 3.2 GB class)."""
    body = QUAD_BINARY[:48] + struct.pack("<I4i", 2**31, 0, 1, 2, 3)
    res = capped("ply", _ply("binary_little_endian", body=body).replace(b"uchar int", b"uint int"))
    assert res["outcome"] == "mesh_error" and "declares 2147483648 items" in res["detail"], res


def test_one_huge_face_among_many_is_refused_with_the_limit(capped):
    """A 965 kB OBJ with one huge face among triangles once took 8.9 GiB; here a 20000-gon
    among 5000 triangles (300 kB) would pad to 800 MB."""
    n = 20000
    text = "".join(f"v {i} {i * i % 7} 0\n" for i in range(n)) + "f 1 2 3\n" * 5000
    text += "f " + " ".join(str(i + 1) for i in range(n)) + "\n"
    res = capped("obj", text.encode())
    assert res["outcome"] == "mesh_error", res
    assert "face 5000 has 20000 vertices" in res["detail"] and "over the limit of" in res["detail"], res


def test_a_huge_polygon_alone_is_read(tmp_path):
    """The limit is relative: a 5000-gon in a small file is a mesh."""
    t = np.linspace(0, 2 * np.pi, 5000, endpoint=False)
    m = Mesh(np.c_[np.cos(t), np.sin(t), np.zeros_like(t)], [list(range(5000))])
    write_mesh(tmp_path / "cap.ply", m)
    assert read_mesh(tmp_path / "cap.ply").face_sizes.tolist() == [5000]


def test_a_long_token_in_an_stl_costs_its_own_size(capped):
    """A 300 kB STL with one long token once asked for 15 GiB (a fixed-width string array)."""
    facet = b"facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
    res = capped("stl", b"solid x\n" + facet * 2000 + b"A" * 300000 + b"\nendsolid\n")
    assert res["outcome"] == "mesh_error" and "in facet 2000, expected 'facet'" in res["detail"], res
    assert res["peak"] < 40 << 20, res


def test_a_fan_of_thousands_of_triangles_is_refused_with_the_limit(tmp_path):
    k = 3000  # one vertex in 3000 triangles, in a mesh of 3000 vertices: stars padded to 3000 x 3000
    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    V = np.r_[[[0, 0, 0]], np.c_[np.cos(t), np.sin(t), np.zeros(k)]]
    F = [[0, 1 + i, 1 + (i + 1) % k] for i in range(k)]
    with pytest.raises(MeshError, match=r"vertex 0 is a corner of 3000 faces.* over the limit of 1048576"):
        Mesh(V, F)


# -- every fault a MeshError naming the place -------------------------------------------------------
@pytest.mark.parametrize("old,new,expect", [
    ("element vertex 4", "element vertex \u00b2", ":3:"),  # a unicode digit once gave a raw ValueError
    ("element vertex 4", "element vertex -4", ":3:"),
    ("property float x", "property flaot x", ":4:"),
    ("property list uchar int", "property list float int", ":8:"),
    ("format ascii 1.0", "format ascii", ":2:"),
])
def test_malformed_header_is_a_mesh_error_on_its_line(tmp_path, old, new, expect):
    path = tmp_path / "h.ply"
    path.write_bytes(_ply("ascii").decode().replace(old, new, 1).encode())
    with pytest.raises(MeshError) as err:
        read_mesh(path)
    assert str(err.value).startswith(f"{path}{expect}") and "\n" not in str(err.value)


# -- nothing silently wrong ------------------------------------------------------------------------
@pytest.mark.parametrize("name,data,facts", [
    ("extra.off", "OFF\n4 1 0\n" + QUAD_ASCII + "3 0 1 2\n", [":8:", "after the last face"]),
    ("short.off", "OFF\n4 2 0\n" + QUAD_ASCII, [":7:", "file ends after 1 of 2 faces"]),
    ("extra.ply", _ply("ascii", body=(QUAD_ASCII + "3 0 1 2\n").encode()),
     [":15:", "after the last record of element 'face'"]),
    ("extra-binary.ply", _ply("binary_little_endian", body=QUAD_BINARY + struct.pack("<B3i", 3, 0, 1, 2)),
     ["byte", "13 byte(s) after the last record of element 'face'"]),
    ("short-binary.ply", _ply("binary_little_endian", body=QUAD_BINARY[:-3]),
     ["byte", "file ends inside element 'face' record 0 of 1"]),
])
def test_data_beyond_or_short_of_the_counts_is_refused(tmp_path, name, data, facts):
    path = tmp_path / name
    path.write_bytes(data if isinstance(data, bytes) else data.encode())
    with pytest.raises(MeshError) as err:
        read_mesh(path)
    for fact in facts:
        assert fact in str(err.value), (fact, str(err.value))


def test_binary_ply_may_end_with_a_newline(tmp_path):
    path = tmp_path / "nl.ply"
    path.write_bytes(_ply("binary_little_endian") + b"\n")
    assert read_mesh(path).n_faces == 1


@pytest.mark.parametrize("name", ["loop", "vertex", "facet", "endloop outer", ""])
def test_stl_solid_names_are_names(tmp_path, name):
    facet = "facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n endloop\nendfacet\n"
    path = tmp_path / "named.stl"
    path.write_text(f"solid {name}\n{facet}endsolid {name}\nsolid second\n{facet.replace('0 1 0', '0 -1 0')}"
                    "endsolid second\n")
    mesh = read_mesh(path)
    assert mesh.n_faces == 2 and mesh.n_vertices == 4


@pytest.mark.parametrize("ext", ["obj", "off", "ply", "stl"])
def test_a_byte_order_mark_is_skipped(tmp_path, ext):
    texts = {"obj": QUAD_OBJ, "off": "OFF\n4 1 0\n" + QUAD_ASCII, "ply": _ply("ascii").decode(),
             "stl": "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
                    "endfacet\nendsolid s\n"}
    plain, bom = tmp_path / f"plain.{ext}", tmp_path / f"bom.{ext}"
    plain.write_text(texts[ext])
    bom.write_bytes(b"\xef\xbb\xbf" + texts[ext].encode())
    a, b = read_mesh(plain), read_mesh(bom)
    assert np.array_equal(a.V, b.V) and np.array_equal(a.F, b.F)


def test_an_outlier_vertex_is_named_not_called_a_zero_length_edge(tmp_path):
    path = tmp_path / "outlier.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 1e15 1 0\nf 1 2 3 4\nf 2 5 6 3\n")
    with pytest.raises(MeshError) as err:
        read_mesh(path)
    msg = str(err.value)
    assert "zero-length" not in msg and msg.startswith(f"{path}:8: face 1") and "stray vertex" in msg, msg


def test_a_mesh_far_from_the_origin_or_tiny_is_valid():
    g = shapes.grid(4, 4, height=lambda x, y: 0.1 * x * y)
    for scale, shift in [(1e-300, 0.0), (1e300, 0.0), (1.0, 1e12), (1e-6, 1e3)]:
        m = Mesh(g.V * scale + shift, g.F)
        assert m.n_faces == g.n_faces


@pytest.mark.parametrize("V,what", [
    ([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]], "collinear"),
    ([[0, 0, 0], [1, 0, 0], [1, 1e-12, 0], [0, 1e-12, 0]], "sliver"),
    ([[0, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0]], "bow-tie"),
])
def test_a_zero_area_face_is_refused_before_any_optimization(tmp_path, V, what):
    path = tmp_path / f"{what}.obj"
    path.write_text("".join("v %r %r %r\n" % tuple(map(float, v)) for v in V) + "f 1 2 3 4\n")
    with pytest.raises(MeshError, match=r":5: face 0 \[0, 1, 2, 3\] has zero area"):
        read_mesh(path)
    r = subprocess.run([sys.executable, "-m", "fabricate", "optimize", str(path), "-o", str(tmp_path / "o.obj")],
                       capture_output=True, text=True, cwd=REPO, env=dict(os.environ, PYTHONPATH=str(REPO)),
                       timeout=120)
    assert r.returncode == 2 and "has zero area" in r.stderr and "Traceback" not in r.stderr, r.stderr


def test_a_zero_area_triangle_is_noted_not_refused():
    """A sliver triangle in a surface to remesh is harmless; it is said, not refused."""
    flat = Mesh([[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 1, 0]], [[0, 1, 3], [1, 2, 3], [0, 2, 1]])
    assert any("1 zero-area triangle(s), the first: face 2 [0, 2, 1]" in n for n in flat.notes), flat.notes
    assert not Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0]], [[0, 1, 2]]).notes


def test_a_thin_but_real_panel_is_accepted():
    Mesh([[0, 0, 0], [1, 0, 0], [1, 1e-6, 0], [0, 1e-6, 0]], [[0, 1, 2, 3]])  # 1 m x 1 micrometre


def test_a_folder_a_pipe_and_a_missing_file_are_told_apart(tmp_path):
    (tmp_path / "dir.obj").mkdir()
    with pytest.raises(MeshError, match=r"dir\.obj: is a folder"):
        read_mesh(tmp_path / "dir.obj")
    fifo = tmp_path / "pipe.obj"
    os.mkfifo(fifo)  # like /dev/zero, reading it might never end
    with pytest.raises(MeshError, match=r"pipe\.obj: is not a regular file"):
        read_mesh(fifo)
    with pytest.raises(MeshError, match=r"gone\.obj: no such file"):
        read_mesh(tmp_path / "gone.obj")


# -- measures at any scale, valid JSON ---------------------------------------------------------------
def _strict(text: str):
    def bad(token):
        raise AssertionError(f"invalid JSON constant {token}")
    return json.loads(text, parse_constant=bad)


@pytest.mark.parametrize("scale", [1e-300, 1e-100, 1e154, 1e200, 1e300])
def test_measures_are_scale_free(scale):
    m = shapes.perturbed(shapes.revolution(shapes.dome_profile(k=4), 6), 0.05, seed=1)
    ref, big = summary(m), summary(m.with_vertices(m.V * scale))
    for key in ("planarity", "conical", "circular", "fairness"):
        assert math.isclose(big[key]["max"], ref[key]["max"], rel_tol=1e-9), (key, scale)
        assert big[key]["worst"] == ref[key]["worst"]
    assert big["vertex_types"] == ref["vertex_types"]
    assert math.isclose(big["angle_deg"]["mean"], ref["angle_deg"]["mean"], rel_tol=1e-12)
    assert math.isclose(big["edge_length"]["max"], ref["edge_length"]["max"] * scale, rel_tol=1e-12)
    assert math.isclose(big["mesh"]["bbox_diagonal"], ref["mesh"]["bbox_diagonal"] * scale, rel_tol=1e-12)


def test_measure_prints_valid_json_at_1e200(tmp_path):
    m = shapes.perturbed(shapes.revolution(shapes.dome_profile(k=4), 6), 0.05, seed=1)
    path = tmp_path / "huge.ply"
    write_mesh(path, m.with_vertices(m.V * 1e200))
    r = subprocess.run([sys.executable, "-m", "fabricate", "measure", str(path)], capture_output=True, text=True,
                       cwd=REPO, env=dict(os.environ, PYTHONPATH=str(REPO)), timeout=120)
    assert r.returncode == 0, r.stderr
    out = _strict(r.stdout)
    assert out["face_area"]["max"] is None  # 1e400 m2 is beyond float64: null, and said so
    assert any("face_area.max is inf" in n for n in out["notes"])
    assert math.isclose(out["planarity"]["max"], summary(m)["planarity"]["max"], rel_tol=1e-9)
