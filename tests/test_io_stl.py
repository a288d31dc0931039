"""STL input: read only, a triangle soup whose corners are welded into the surface; errors name the line."""
import struct

import numpy as np
import pytest

from optimize import MeshError
from optimize.mesh.io import read_mesh, write_mesh


def _stl_binary(path, tris, header=b"solid written by a modeller"):

    with open(path, "wb") as fh:
        fh.write(header.ljust(80, b" "))
        fh.write(struct.pack("<I", len(tris)))
        for tri in np.asarray(tris, dtype=np.float32):
            fh.write(np.zeros(3, np.float32).tobytes() + tri.tobytes() + b"\0\0")


def _stl_ascii(path, tris, fmt="%.9g"):
    lines = ["solid roof"]
    for tri in tris:
        lines += ["  facet normal 0 0 1", "    outer loop"]
        lines += ["      vertex " + " ".join(fmt % c for c in v) for v in tri]
        lines += ["    endloop", "  endfacet"]
    path.write_text("\n".join(lines + ["endsolid roof"]) + "\n")


@pytest.mark.parametrize("kind", ["binary", "ascii"])
def test_stl_triangle_soup_is_welded_into_the_surface(tmp_path, kind):
    from optimize.remesh.surfaces import holed_roof

    roof = holed_roof()
    tris = roof.V[roof.F]
    path = tmp_path / f"roof-{kind}.stl"
    if kind == "binary":  # float32 corners
        _stl_binary(path, tris)
        want = roof.V.astype(np.float32).astype(np.float64)
    else:  # text written with every digit of a double
        _stl_ascii(path, tris, fmt="%.17g")
        want = roof.V
    back = read_mesh(path)
    assert back.n_vertices == roof.n_vertices and back.n_faces == roof.n_faces
    assert len(back.topology.boundary_loops) == 2  # welded: the soup became one surface with its hole
    got = back.V[np.lexsort(back.V.T[::-1])]
    want = want[np.lexsort(want.T[::-1])]
    np.testing.assert_array_equal(got, want)
    assert any("welded" in n for n in back.notes)


def test_stl_errors_name_the_line_or_say_what_was_expected(tmp_path):
    tri = [[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0], [0, 1, 0]]]
    trunc = tmp_path / "trunc.stl"
    _stl_binary(trunc, tri, header=b"binary")
    trunc.write_bytes(trunc.read_bytes()[:-7])
    with pytest.raises(MeshError, match=r"trunc.stl: \d+ bytes: neither a binary STL .* nor an ASCII STL"):
        read_mesh(trunc)
    four = tmp_path / "four.stl"
    _stl_ascii(four, tri)
    text = four.read_text().splitlines()
    text.insert(5, "      vertex 2 2 0")  # a fourth vertex in the first facet
    four.write_text("\n".join(text) + "\n")
    with pytest.raises(MeshError, match=r"four.stl:7: facet 0 has more than 3 vertices, expected 3"):
        read_mesh(four)
    nan = tmp_path / "word.stl"
    _stl_ascii(nan, tri)
    nan.write_text(nan.read_text().replace("vertex 1 1 0", "vertex 1 one 0"))
    with pytest.raises(MeshError, match=r"word.stl:\d+: 'one' is not a number, expected a vertex coordinate"):
        read_mesh(nan)
    sliver = tmp_path / "sliver.stl"
    _stl_binary(sliver, tri + [[[0, 0, 0], [0, 0, 0], [1, 0, 0]]])  # a corner repeated
    m = read_mesh(sliver)
    assert m.n_faces == 2 and any("1 degenerate triangle(s) dropped" in n for n in m.notes)
    with pytest.raises(MeshError, match="STL is read here, not written"):
        write_mesh(tmp_path / "out.stl", m)
