"""The fast paths of the mesh file checks give what the plain ones give, on good and broken files."""
import re

import manifold3d
import numpy as np
import pytest
from cad_fixtures import dome_parts, rezip_3mf

import fabricate.check_mesh as cm
from fabricate.check_mesh import _weld_parts, check_3mf
from fabricate.export import verify, write_3mf, write_bom, write_stl
from fabricate.export.bom import read_bom
from fabricate.export.threemf import read_3mf
from fabricate.export.threemf_text import read_3mf_text
from fabricate.export.verify import Solid, solids_of
from optimize.errors import ExportError


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    parts = dome_parts(6, 3)
    out = tmp_path_factory.mktemp("meshspeed")
    for name, fn in (("model.3mf", write_3mf), ("model.stl", write_stl), ("bom.csv", write_bom)):
        fn(parts, out / name)
    return out


def _same(a, b):
    return list(a) == list(b) and all(np.array_equal(a[k][0], b[k][0]) and np.array_equal(a[k][1], b[k][1])
                                      for k in a)


def test_blocks_with_line_breaks_and_long_indices(folder, tmp_path):
    spaced = rezip_3mf(folder / "model.3mf", tmp_path / "a.3mf",
                    lambda t: t.replace(b"/><vertex ", b"/>\n  <vertex ").replace(b"/><triangle ", b"/>\n<triangle "))
    assert _same(read_3mf_text(spaced), read_3mf(folder / "model.3mf"))
    padded = rezip_3mf(folder / "model.3mf", tmp_path / "b.3mf", lambda t: re.sub(rb'v2="(\d+)"', rb'v2="000\1"', t))
    assert _same(read_3mf_text(padded), read_3mf(folder / "model.3mf"))          # leading zeros: same numbers
    huge = rezip_3mf(folder / "model.3mf", tmp_path / "c.3mf", lambda t: re.sub(rb'v3="\d+"', b'v3="1' + b"0" * 17 + b'"',
                                                                               t, count=1))
    with pytest.raises(ExportError, match="triangle index beyond"):              # 18 digits: the float reader
        read_3mf_text(huge)


def _per_object(objects, holes):
    """The names that are not a closed 2-manifold of their genus, one manifold3d mesh per object."""
    out = []
    for n, (V, T) in objects.items():
        m = manifold3d.Manifold(manifold3d.Mesh64(vert_properties=np.ascontiguousarray(V, np.float64),
                                                  tri_verts=np.ascontiguousarray(T, np.uint64)))
        if m.status().name != "NoError" or m.genus() != holes.get(n, 0):
            out.append(n)
    return out


def _flip_first_triangle(t, k):
    """The model with the first triangle of object ``k`` (0-based) turned over."""
    at = [m.start() for m in re.finditer(rb"<object ", t)][k]
    m = re.compile(rb'<triangle v1="(\d+)" v2="(\d+)" v3="(\d+)"/>').search(t, at)
    return t[:m.start()] + b'<triangle v1="%s" v2="%s" v3="%s"/>' % (m[1], m[3], m[2]) + t[m.end():]


def test_manifold_once_per_topology_names_what_each_object_alone_names(folder, tmp_path):
    from fabricate.check import _holes

    bom = read_bom(folder / "bom.csv")
    good, _ = check_3mf(folder / "model.3mf", bom)
    assert good["pass"] and good["not_manifold"] == [] and good["not_one_piece"] == []
    broken = rezip_3mf(folder / "model.3mf", tmp_path / "d.3mf", lambda t: _flip_first_triangle(t, 2))
    result, _ = check_3mf(broken, bom)
    objects = read_3mf_text(broken)
    expected = _per_object(objects, _holes(bom))
    assert not result["pass"] and expected and result["not_manifold"] == expected
    assert result["not_manifold"] == [list(objects)[2]]


def test_an_object_in_two_pieces_is_named(folder, tmp_path):
    bom = read_bom(folder / "bom.csv")

    def twice(t):                          # object 1's mesh and a copy of it beside it, in one object
        at = [m.start() for m in re.finditer(rb"<object ", t)][1]
        v0, v1 = t.index(b"<vertices>", at) + 10, t.index(b"</vertices>", at)
        t0, t1 = t.index(b"<triangles>", at) + 11, t.index(b"</triangles>", at)
        n = t[v0:v1].count(b"<vertex ")
        copy = re.sub(rb'z="([^"]*)"', lambda m: b'z="%r"' % (float(m[1]) + 1e4), t[v0:v1])
        tris = re.sub(rb'"(\d+)"', lambda m: b'"%d"' % (int(m[1]) + n), t[t0:t1])
        return t[:v1] + copy + t[v1:t1] + tris + t[t1:]

    result, _ = check_3mf(rezip_3mf(folder / "model.3mf", tmp_path / "e.3mf", twice), bom)
    assert not result["pass"] and result["not_one_piece"] == [1]


def test_welding_runs_of_parts_is_one_sort(monkeypatch):
    rng = np.random.default_rng(3)
    counts = rng.integers(1, 9, 40)
    P = rng.integers(-2, 3, (int(counts.sum()), 3, 3)).astype(np.float32)   # many equal corners, -0.0 too
    P[0, 0, 0] = -0.0
    whole = _weld_parts(P, counts)
    monkeypatch.setattr(cm, "WELD", 7)                                       # runs of a few parts
    runs = _weld_parts(P, counts)
    assert np.array_equal(whole[0], runs[0]) and np.array_equal(whole[1], runs[1])
    part = np.repeat(np.arange(len(counts)), 3 * counts).reshape(-1, 3)
    assert np.array_equal(runs[0][runs[1]], P + np.float32(0.0))             # every corner kept
    owner = np.full(len(runs[0]), -1)
    owner[runs[1].ravel()] = part.ravel()
    assert (owner[runs[1]] == part).all()                                    # no vertex shared by two parts


def test_chunked_solids_equal_one_at_a_time(folder, monkeypatch):
    monkeypatch.setattr(verify, "PER_CHUNK", 100)                           # many chunks, some of one mesh
    objects = read_3mf_text(folder / "model.3mf")
    batch = solids_of(objects)
    for name, (V, T) in objects.items():
        one, b = Solid(name, V, T), batch[name]
        assert one.convex == b.convex and one.tol == b.tol
        assert np.allclose(one.normals, b.normals, atol=1e-12) and np.allclose(one.offsets, b.offsets)
        assert len(one.face_support[0]) == len(b.face_support[0])


def test_a_3mf_object_with_a_nan_vertex_fails_its_volume(tmp_path):
    """Objects of one topology share the manifold test (it depends on the triangles only); a NaN
    coordinate makes that object's volume NaN, which fails it (NaN > tol is false)."""
    import re

    from cad_fixtures import dome_parts

    from fabricate.check_mesh import check_3mf
    from fabricate.export import write_3mf, write_bom
    from fabricate.export.bom import read_bom

    parts = dome_parts(4, 2)
    write_3mf(parts, tmp_path / "model.3mf")
    write_bom(parts, tmp_path / "bom.csv")
    bom = read_bom(tmp_path / "bom.csv")
    assert check_3mf(tmp_path / "model.3mf", bom)[0]["pass"]
    rezip_3mf(tmp_path / "model.3mf", tmp_path / "bad.3mf",
              lambda m: re.sub(rb'(<vertex x=")[^"]+', rb"\g<1>nan", m, count=1))
    res = check_3mf(tmp_path / "bad.3mf", bom)[0]
    assert not res["pass"]
