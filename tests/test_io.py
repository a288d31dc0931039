"""Mesh files: exact write-read round trips, format features, one test per malformed input (STL: test_io_stl.py)."""
import struct

import numpy as np
import pytest

from optimize import ExportError, Mesh, MeshError
from optimize.modelling import shapes
from optimize.mesh.io import read_mesh, write_mesh
from optimize.mesh.io.ply import format_ply

#: (file extension, write_mesh keywords or a PLY encoding written with format_ply)
FORMATS = [("obj", {}), ("off", {}), ("ply", {}), ("ply", {"binary": False}),
           ("ply", "binary_big_endian")]
FORMAT_IDS = ["obj", "off", "ply-le", "ply-ascii", "ply-be"]


def _write(path, mesh, how):
    if isinstance(how, str):
        path.write_bytes(format_ply(mesh, how))
    else:
        write_mesh(path, mesh, **how)


def _awkward_meshes(revolution):
    """Meshes whose numbers and faces a lossy writer would change."""
    noisy = shapes.perturbed(revolution, 0.05, seed=3)
    far = noisy.with_vertices(noisy.V / 3.0 + [1e5, -2.5e4, np.pi])
    tiny = noisy.with_vertices(noisy.V * 1e-300)
    a = np.linspace(0, 2 * np.pi, 300, endpoint=False)
    disc = Mesh(np.stack([np.cos(a), np.sin(a), 1e-3 * np.sin(5 * a)], axis=1),
                [list(range(300))], name="300-gon")  # more than 255 corners: uint counts
    mixed = Mesh([[0, 0, 0], [1, 0, 0], [1, 1, 0.1], [0, 1, 0], [2, 0, 0], [2, 1, 0], [3, 0.5, -0.0]],
                 [[0, 1, 2, 3], [1, 4, 5, 2], [4, 6, 5]], name="mixed")
    return {"far": far, "tiny": tiny, "disc": disc, "mixed": mixed}


# -- round trips ------------------------------------------------------------------------
@pytest.mark.parametrize("ext,how", FORMATS, ids=FORMAT_IDS)
def test_round_trip_is_exact(tmp_path, revolution, ext, how):
    for key, mesh in _awkward_meshes(revolution).items():
        path = tmp_path / f"{key}.{ext}"
        _write(path, mesh, how)
        back = read_mesh(path)
        assert back.V.dtype == np.float64 and back.F.dtype == np.int64
        assert np.array_equal(back.V, mesh.V), key
        assert np.array_equal(back.F, mesh.F), key
        assert back.name == str(path) and back.notes == []


@pytest.mark.parametrize("ext,how", FORMATS[:4], ids=FORMAT_IDS[:4])
def test_header_comments_are_written_and_read_past(tmp_path, revolution, ext, how):
    """A result that missed its tolerance is marked in the file itself; readers skip the mark."""
    path = tmp_path / f"marked.{ext}"
    write_mesh(path, revolution, comments=["NOT CONVERGED: conical stalled\nafter 3 iterations", "two"], **how)
    head = path.read_bytes()[:400].decode("ascii", "replace")
    assert "NOT CONVERGED: conical stalled after 3 iterations" in head and "two" in head
    back = read_mesh(path)
    assert np.array_equal(back.V, revolution.V) and np.array_equal(back.F, revolution.F)


@pytest.mark.parametrize("ext,how", FORMATS, ids=FORMAT_IDS)
def test_round_trip_of_the_tunnel_and_the_capped_cylinder(tmp_path, tunnel_path, cylinder_path, ext, how):
    for src in (tunnel_path, cylinder_path):
        mesh = read_mesh(src)
        path = tmp_path / f"{src.stem}.{ext}"
        _write(path, mesh, how)
        back = read_mesh(path)
        assert np.array_equal(back.V, mesh.V) and np.array_equal(back.F, mesh.F)


def test_write_replaces_atomically(tmp_path, quad, grid3x3):
    path = tmp_path / "m.obj"
    write_mesh(path, quad)
    write_mesh(path, grid3x3)
    assert np.array_equal(read_mesh(path).V, grid3x3.V)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.obj"]  # no temporary left


def test_failed_write_leaves_nothing(tmp_path, quad):
    target = tmp_path / "taken.off"
    target.mkdir()  # a folder where the file should go: the rename fails
    with pytest.raises(ExportError, match="taken.off"):
        write_mesh(target, quad)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["taken.off"] and target.is_dir()


def test_write_unknown_format(tmp_path, quad):
    with pytest.raises(MeshError, match=r"unknown mesh extension '\.dae'.*\.obj, \.off, \.ply"):
        write_mesh(tmp_path / "m.dae", quad)
    assert list(tmp_path.iterdir()) == []


def test_format_from_argument_and_upper_case_extension(tmp_path, grid3x3):
    write_mesh(tmp_path / "m.txt", grid3x3, fmt="off")
    assert (tmp_path / "m.txt").read_text().startswith("OFF\n")
    assert np.array_equal(read_mesh(tmp_path / "m.txt", fmt="OFF").V, grid3x3.V)
    write_mesh(tmp_path / "M.OBJ", grid3x3)
    assert np.array_equal(read_mesh(tmp_path / "M.OBJ").F, grid3x3.F)


def test_ply_writes_binary_little_endian_by_default(tmp_path, quad):
    write_mesh(tmp_path / "q.ply", quad)
    data = (tmp_path / "q.ply").read_bytes()
    assert b"format binary_little_endian 1.0" in data
    body = data[data.index(b"end_header\n") + 11:]
    assert body[:24] == struct.pack("<3d", 0.0, 0.0, 0.0) and len(body) == 4 * 24 + 1 + 16


# -- the shipped and the built-in meshes ---------------------------------------------------
def test_read_tunnel(tunnel_path):
    m = read_mesh(tunnel_path)
    assert (m.n_vertices, m.n_faces) == (807, 784) and m.is_quad
    lines = [ln for ln in tunnel_path.read_text().splitlines() if ln and not ln.startswith("#")]
    assert lines[0] == "OFF" and lines[1].split()[:2] == ["807", "784"]
    assert m.V[0].tolist() == [float(x) for x in lines[2].split()]  # first vertex line
    assert m.F[-1].tolist() == [int(x) for x in lines[-1].split()[1:]]  # last face line


def test_read_cylinder(cylinder_path):
    m = read_mesh(cylinder_path)
    assert m.n_vertices == 220
    assert np.bincount(m.face_sizes).tolist()[4] == 200 and np.sum(m.face_sizes == 20) == 2
    assert m.F[0, :4].tolist() == [0, 1, 21, 20]  # 'f 1 2 22 21'
    assert m.topology.boundary_loops == [] and m.notes == []


# -- format features ----------------------------------------------------------------------
SQUARE_STRIP = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0], [2, 1, 0], [3, 0.5, 0]],
                        float)


def test_obj_features(tmp_path):
    text = """# exported by hand
mtllib none.mtl
o strip
v 0 0 0 1.0
v 1 0 0 0.5 0.5 0.5
v 1 1 0
v 0 1 \\
  0
vt 0 0
vn 0 0 1
g part
usemtl glass
s off
f 1/1/1 2/1/1 3/1/1 4/1/1   # a quad with v/vt/vn tokens
v 2 0 0
v 2 1 0
f -5//1 -2//1 -1//1 -4//1
l 1 2
p 3
v 3 0.5 0
f 5/1 7/1 \\
 6/1
zz unknown record
"""
    path = tmp_path / "features.obj"
    path.write_text(text)
    m = read_mesh(path)
    assert np.array_equal(m.V, SQUARE_STRIP)
    assert m.faces_list() == [[0, 1, 2, 3], [1, 4, 5, 2], [4, 6, 5]]
    assert len(m.notes) == 1 and "'zz'" in m.notes[0] and ":" in m.notes[0] and "line 23" in m.notes[0]


def test_off_features_wrapped_records_and_colours(tmp_path):
    text = """# leading comment
COFF
# the counts
7 3 0
0 0 0 255 0 0 255
1 0 0 255 0 0 255
1 1 0  0 255 0 255
0 1 0 0 0 255 255
2 0 0 1 1 1 1
2 1 0 1 1 1 1
3 0.5 0 1 1 1 1
4 0 1 2
3 0.5 0.5 0.5 1
4 1 4
  5 2
3 4 6 5 255 0 0
"""
    path = tmp_path / "features.off"
    path.write_text(text)
    m = read_mesh(path)
    assert np.array_equal(m.V, SQUARE_STRIP)
    assert m.faces_list() == [[0, 1, 2, 3], [1, 4, 5, 2], [4, 6, 5]]


@pytest.mark.parametrize("head", ["OFF 4 1 0\n", "4 1 0\n", "NOFF\n4 1\n", "OFF\n4\n1 0\n"],
                         ids=["counts-on-header", "no-header", "noff", "counts-wrapped"])
def test_off_header_variants(tmp_path, head):
    normals = " 0 0 1" if head.startswith("NOFF") else ""
    body = "".join(f"{x} {y} 0{normals}\n" for x, y in [(0, 0), (1, 0), (1, 1), (0, 1)])
    path = tmp_path / "h.off"
    path.write_text(head + body + "4 0 1 2 3\n")
    m = read_mesh(path)
    assert m.faces_list() == [[0, 1, 2, 3]] and m.V[2].tolist() == [1, 1, 0]


def _hand_ply(endian: str, faces, extra_element=True) -> bytes:
    """A binary PLY written with struct (independent of the writer): float vertices with
    colour, int counts and uint indices, a flag after the list, and an 'edge' element."""
    V = SQUARE_STRIP[: max(max(f) for f in faces) + 1]
    enc = "binary_little_endian" if endian == "<" else "binary_big_endian"
    head = ["ply", f"format {enc} 1.0", "comment hand made", "obj_info test",
            f"element vertex {len(V)}", "property float x", "property uchar red", "property float y",
            "property float z", "property uchar alpha",
            f"element face {len(faces)}", "property list int uint vertex_indices",
            "property uchar flags"]
    if extra_element:
        head += ["element edge 1", "property int vertex1", "property int vertex2"]
    out = ("\n".join(head + ["end_header"]) + "\n").encode("ascii")
    for x, y, z in V:
        out += struct.pack(endian + "fBffB", x, 200, y, z, 255)
    for f in faces:
        out += struct.pack(endian + f"i{len(f)}IB", len(f), *f, 7)
    if extra_element:
        out += struct.pack(endian + "ii", 0, 1)
    return out


@pytest.mark.parametrize("endian", ["<", ">"], ids=["little", "big"])
@pytest.mark.parametrize("faces", [[[0, 1, 2, 3], [1, 4, 5, 2]], [[0, 1, 2, 3], [1, 4, 5, 2], [4, 6, 5]]],
                         ids=["quads", "mixed"])
def test_binary_ply_written_by_hand(tmp_path, endian, faces):
    path = tmp_path / "hand.ply"
    path.write_bytes(_hand_ply(endian, faces))
    m = read_mesh(path)
    used = sorted({i for f in faces for i in f})
    assert np.array_equal(m.V, SQUARE_STRIP[: len(used)])
    assert m.faces_list() == faces


def test_ascii_ply_with_extra_properties(tmp_path):
    text = ("ply\nformat ascii 1.0\ncomment hi\nelement vertex 7\nproperty double x\n"
            "property double y\nproperty double z\nproperty uchar red\n"
            "element face 3\nproperty uchar flag\nproperty list uchar int vertex_index\nend_header\n"
            + "".join(f"{x!r} {y!r} {z!r} 9\n" for x, y, z in SQUARE_STRIP.tolist())
            + "1 4 0 1 2 3\n0 4 1 4\n 5 2\n1 3 4 6 5\n")
    path = tmp_path / "extra.ply"
    path.write_text(text)
    m = read_mesh(path)
    assert np.array_equal(m.V, SQUARE_STRIP)
    assert m.faces_list() == [[0, 1, 2, 3], [1, 4, 5, 2], [4, 6, 5]]


# -- one test per malformed input -------------------------------------------------------
QUAD_OBJ = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
QUAD_OFF = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
PLY_HEAD = ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n")
PLY_QUAD = PLY_HEAD + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"
TRIPLE_EDGE_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n"


def _bin_quad(cut=None, index=3):
    m = Mesh(SQUARE_STRIP[:4], [[0, 1, 2, 3]])
    data = format_ply(m)
    if index != 3:
        data = data[:-4] + struct.pack("<i", index)
    return data[:cut] if cut else data


MALFORMED = {
    # id: (file name, content, facts the message must contain after "path")
    "empty-file": ("e.obj", "", [":1:", "empty file"]),
    "blank-file": ("b.off", "\n  \n\t\n", [":1:", "empty file"]),
    "only-comments": ("c.off", "# nothing here\n", [":1:", "no data"]),
    "obj-bad-number": ("n.obj", "v 0 0 0\nv 1 0,5 0\n", [":2:", "'0,5' is not a number", "vertex 2"]),
    "obj-short-vertex": ("s.obj", QUAD_OBJ + "v 1 2\nf 1 2 3 4\n", [":5:", "2 number(s)"]),
    "obj-bad-index": ("i.obj", QUAD_OBJ + "f 1 2 x 4\n", [":5:", "'x' is not an integer", "index 3"]),
    "obj-index-out-of-range": ("r.obj", QUAD_OBJ + "f 1 2 3 9\n", [":5:", "vertex 9", "expected 1..4"]),
    "obj-index-zero": ("z.obj", QUAD_OBJ + "f 0 1 2\n", [":5:", "vertex index 0"]),
    "obj-relative-too-far": ("t.obj", QUAD_OBJ + "f -1 -2 -5\n", [":5:", "relative index -5",
                                                                   "4 defined so far"]),
    "obj-two-vertex-face": ("f.obj", QUAD_OBJ + "f 1 2 3 4\nf 1 2\n", [":6:", "face 1",
                                                                        "2 vertex index(es)",
                                                                        "at least 3"]),
    "obj-no-faces": ("v.obj", QUAD_OBJ, ["no faces (4 vertices)"]),
    "obj-nan": ("nan.obj", QUAD_OBJ.replace("v 1 1 0", "v nan 1 0") + "f 1 2 3 4\n",
                [":3:", "vertex 2", "nan", "expected finite"]),
    "off-inf": ("inf.off", QUAD_OFF.replace("1 1 0", "1 inf 0") + "4 0 1 2 3\n",
                [":5:", "vertex 2", "inf", "expected finite"]),
    "obj-non-manifold": ("nm.obj", TRIPLE_EDGE_OBJ, [":8:", "non-manifold edge [0, 1]", "3 faces"]),
    "obj-repeated-vertex": ("rep.obj", QUAD_OBJ + "f 1 2 3 2\n", [":5:", "face 0", "repeats a vertex"]),
    "obj-zero-length-edge": ("zl.obj", QUAD_OBJ + "v 1 1 0\nf 1 2 5 4\nf 2 3 5\n",
                             [":7:", "face 1", "zero-length edge"]),
    "obj-unused-vertex": ("u.obj", QUAD_OBJ + "v 5 5 5\nf 1 2 3 4\n", [":5:", "vertex 4", "no face"]),
    "off-bad-header": ("h.off", "OF\n4 1 0\n", [":1:", "found 'OF'", "expected an OFF header"]),
    "off-4d": ("d.off", "4OFF\n4 1 0\n", [":1:", "4D or nD"]),
    "off-binary": ("bin.off", "OFF BINARY\n", [":1:", "binary OFF"]),
    "off-bad-counts": ("cnt.off", "OFF\nfour 1 0\n", [":2:", "'four' is not an integer", "counts"]),
    "off-bad-number": ("num.off", QUAD_OFF.replace("1 0 0", "1.0.0 0 0") + "4 0 1 2 3\n",
                       [":4:", "'1.0.0' is not a number", "vertex 1"]),
    "off-bad-face-count": ("fc.off", QUAD_OFF + "x 0 1 2\n", [":7:", "'x' starts face 0"]),
    "off-index-out-of-range": ("oor.off", QUAD_OFF + "4 0 1 2 7\n", [":7:", "vertex 7", "expected 0..3"]),
    "off-two-vertex-face": ("two.off", QUAD_OFF.replace("4 1 0", "4 2 0") + "4 0 1 2 3\n2 0 1\n",
                            [":8:", "face 1", "2 vertex index(es)"]),
    "off-truncated-vertices": ("tv.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1", [":5:", "file ends after 2 of 4 "
                                                                           "vertices", "line 2"]),
    "off-truncated-faces": ("tf.off", QUAD_OFF.replace("4 1 0", "4 2 0") + "4 0 1 2 3\n",
                            [":7:", "file ends after 1 of 2 faces", "4 vertices and 2 faces"]),
    "ply-bad-magic": ("m.ply", "plx\n", [":1:", "expected 'ply'"]),
    "ply-no-end-header": ("eh.ply", "ply\nformat ascii 1.0\nelement vertex 1\n", ["no 'end_header'"]),
    "ply-bad-format": ("bf.ply", PLY_QUAD.replace("format ascii 1.0", "format utf8 1.0"),
                       [":2:", "'format utf8 1.0'", "expected 'format ascii"]),
    "ply-bad-property": ("bp.ply", PLY_QUAD.replace("property float z", "property float128 z"),
                         [":6:", "float128", "expected 'property TYPE NAME'"]),
    "ply-no-face-element": ("nf.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                      "property float y\nproperty float z\nend_header\n0 0 0\n",
                            ["no 'face' element"]),
    "ply-no-z": ("nz.ply", PLY_QUAD.replace("property float z\n", ""), [":3:", "expected scalar x, y and z"]),
    "ply-float-indices": ("fi.ply", PLY_QUAD.replace("uchar int", "uchar float"),
                          [":8:", "expected an integer type"]),
    "ply-ascii-bad-number": ("an.ply", PLY_QUAD.replace("1 1 0", "1 one 0"),
                             [":12:", "'one' is not a number", "vertex 2"]),
    "ply-ascii-bad-count": ("ac.ply", PLY_QUAD.replace("4 0 1 2 3", "four 0 1 2 3"),
                            [":14:", "'four' starts the 'vertex_indices' list"]),
    "ply-ascii-truncated": ("at.ply", PLY_HEAD + "0 0 0\n1 0 0\n1 1 0\n",
                            [":3:", "element 'vertex': 4 records", "only 19 bytes follow the header"]),
    "ply-ascii-data-after-records": ("asf.ply", PLY_QUAD + "3 0 1 2\n",
                                     [":15:", "'3' after the last record of element 'face'",
                                      "1 face as declared"]),
    "off-data-after-faces": ("after.off", QUAD_OFF + "4 0 1 2 3\n3 0 1 2\n",
                             [":8:", "'3' after the last face", "1 faces as declared on line 2"]),
    "ply-ascii-truncated-face": ("atf.ply", PLY_HEAD + "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1",
                                 [":14:", "file ends inside 'face' record 0"]),
    "ply-binary-truncated-vertices": ("btv.ply", _bin_quad(cut=240), [":4:", "element 'vertex': 4 records",
                                                                      "only 37 bytes follow the header"]),
    "ply-binary-truncated-faces": ("btf.ply", _bin_quad(cut=-3), ["byte", "element 'face' record 0 of 1"]),
    "ply-binary-index-out-of-range": ("bir.ply", _bin_quad(index=9), ["byte", "face 0", "vertex 9",
                                                                      "expected 0..3"]),
}


@pytest.mark.parametrize("case", list(MALFORMED))
def test_malformed_input(tmp_path, case):
    name, content, facts = MALFORMED[case]
    path = tmp_path / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    with pytest.raises(MeshError) as err:
        read_mesh(path)
    msg = str(err.value)
    assert msg.startswith(str(path)), msg
    assert "\n" not in msg
    for fact in facts:
        assert fact in msg, (fact, msg)


def _grid_off(drop_at_line=None, wrap=False) -> str:
    """OFF of a 5 x 4 vertex grid (20 vertices, lines 3-22; 12 quads, lines 23-34); the face on line
    ``drop_at_line`` loses its last index; ``wrap`` splits every face record over two lines."""
    m = shapes.grid(5, 4, size=(3.0, 2.0))
    lines = ["OFF", "20 12 0"] + ["%g %g %g" % tuple(v) for v in m.V]
    for f in m.F.tolist():
        rec = ["4"] + [str(i) for i in f]
        if len(lines) + 1 == drop_at_line:
            rec = rec[:-1]
        lines += [" ".join(rec[:3]), "  " + " ".join(rec[3:])] if wrap else [" ".join(rec)]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("line", [23, 28])
def test_off_short_face_is_named_on_its_own_line(tmp_path, line):
    """A face record with too few indices takes the next face's count as its last index; the
    file then ends early.  The message names the short record's line, not the file's end."""
    path = tmp_path / "short.off"
    path.write_text(_grid_off(drop_at_line=line))
    with pytest.raises(MeshError) as err:
        read_mesh(path)
    msg = str(err.value)
    assert msg.startswith(f"{path}:{line}: face {line - 23} "), msg
    assert "3 of its 4 indices" in msg and f"line {line + 1}" in msg and "11 of 12 faces" in msg, msg
    assert "\n" not in msg


def test_off_short_last_face_is_named_where_it_starts(tmp_path):
    path = tmp_path / "last.off"
    text = _grid_off(wrap=True)  # every record over two lines; the last one loses an index
    text = text[: text.rstrip().rindex(" ")] + "\n"
    path.write_text(text)
    with pytest.raises(MeshError) as err:
        read_mesh(path)
    msg = str(err.value)
    assert msg.startswith(f"{path}:45: face 11 "), msg  # lines 45-46 hold face 11
    assert "file ends" in msg and "11 of 12 faces" in msg


def test_off_wrapped_faces_still_read(tmp_path):
    path = tmp_path / "wrapped.off"
    path.write_text(_grid_off(wrap=True))
    assert read_mesh(path).faces_list() == shapes.grid(5, 4).faces_list()


def test_missing_file(tmp_path):
    with pytest.raises(MeshError, match=r"nothing\.obj: no such file"):
        read_mesh(tmp_path / "nothing.obj")


def test_folder_instead_of_file(tmp_path):
    (tmp_path / "dir.off").mkdir()
    with pytest.raises(MeshError, match=r"dir\.off: is a folder"):
        read_mesh(tmp_path / "dir.off")


def test_unknown_extension(tmp_path):
    path = tmp_path / "mesh.dae"
    path.write_text("<COLLADA/>\n")
    with pytest.raises(MeshError, match=r"mesh\.dae: unknown mesh extension '\.dae', expected one of "
                                        r"\.obj, \.off, \.ply, \.stl"):
        read_mesh(path)


def test_unknown_format_argument(tmp_path):
    with pytest.raises(MeshError, match="unknown mesh format 'dae'"):
        read_mesh(tmp_path / "m.obj", fmt="dae")


def test_binary_ply_non_manifold_names_the_byte(tmp_path):
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], float)
    ok = Mesh(V[:4], [[0, 1, 2], [1, 0, 3]])
    data = format_ply(ok).replace(b"element vertex 4", b"element vertex 5").replace(b"element face 2",
                                                                                        b"element face 3")
    head, body = data.split(b"end_header\n")
    body = V.astype("<f8").tobytes() + body[4 * 24:] + struct.pack("<B3i", 3, 0, 1, 4)
    path = tmp_path / "nm.ply"
    path.write_bytes(head + b"end_header\n" + body)
    with pytest.raises(MeshError) as err:
        read_mesh(path)
    face2 = len(head) + 11 + 5 * 24 + 2 * 13  # header, vertices, two triangle records
    assert f"{path}: byte {face2}: non-manifold edge [0, 1]" in str(err.value)


def test_crlf_line_ends_and_latin1_comments(tmp_path, grid3x3):
    for ext, kw in [("obj", {}), ("off", {}), ("ply", {"binary": False})]:
        path = tmp_path / f"crlf.{ext}"
        write_mesh(path, grid3x3, **kw)
        data = path.read_bytes().replace(b"\n", b"\r\n")
        if ext != "ply":
            data = b"# caf\xe9 latin-1 comment\r\n" + data if ext == "obj" else \
                data.replace(b"OFF\r\n", b"OFF\r\n# caf\xe9\r\n", 1)
        path.write_bytes(data)
        back = read_mesh(path)
        assert np.array_equal(back.V, grid3x3.V) and np.array_equal(back.F, grid3x3.F), ext


@pytest.mark.parametrize("ext,how", FORMATS, ids=FORMAT_IDS)
def test_damaged_files_raise_mesh_error_only(tmp_path, ext, how):
    """Seeded damage (cuts, flipped bytes, deletions, insertions): a Mesh or a one-line MeshError."""
    mesh = shapes.perturbed(shapes.revolution(shapes.dome_profile(k=4), 6), 0.05, seed=1)
    src = tmp_path / f"src.{ext}"
    _write(src, mesh, how)
    data = src.read_bytes()
    rng = np.random.default_rng(2024)
    alphabet = np.frombuffer(b" 0123456789-.\n#/\\enaif\x00\xff", dtype=np.uint8)
    for _ in range(150):
        b = bytearray(data)
        i = int(rng.integers(len(b)))
        op = int(rng.integers(4))
        if op == 0:
            del b[i:]
        elif op == 1:
            b[i] = int(rng.integers(256))
        elif op == 2:
            del b[i:i + int(rng.integers(1, 20))]
        else:
            b[i:i] = rng.choice(alphabet, int(rng.integers(1, 6))).tobytes()
        path = tmp_path / f"damaged.{ext}"
        path.write_bytes(bytes(b))
        try:
            read_mesh(path)
        except MeshError as exc:
            assert str(exc).startswith(str(path)) and "\n" not in str(exc)

