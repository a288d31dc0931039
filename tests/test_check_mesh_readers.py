"""The full check's batched readers and tests read what the per-part ones read, and still fail broken files."""
import dataclasses
import re

import numpy as np
import pytest
from cad_fixtures import dome_parts, rezip_3mf

from fabricate.check import check_outputs
from fabricate.check_mesh import _weld_parts
from fabricate.export import write_3mf, write_bom, write_dxf, write_stl, write_svg
from fabricate.export.threemf import read_3mf
from fabricate.export.threemf_text import read_3mf_text
from fabricate.export.verify import Solid, outline_areas, polygon_measures, solids_of
from optimize.errors import ExportError


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    parts = dome_parts(6, 3)
    out = tmp_path_factory.mktemp("meshread")
    for name, fn in (("model.3mf", write_3mf), ("model.stl", write_stl), ("outlines.dxf", write_dxf),
                     ("outlines.svg", write_svg), ("bom.csv", write_bom)):
        fn(parts, out / name)
    return out


def test_3mf_text_reader_reads_what_elementtree_reads(folder):
    mine, theirs = read_3mf_text(folder / "model.3mf"), read_3mf(folder / "model.3mf")
    assert list(mine) == list(theirs)
    assert all(np.array_equal(mine[k][0], theirs[k][0]) and np.array_equal(mine[k][1], theirs[k][1]) for k in mine)


def test_3mf_other_attribute_order_malformed_xml_and_bad_index(folder, tmp_path):
    swapped = rezip_3mf(folder / "model.3mf", tmp_path / "a.3mf",
                     lambda t: re.sub(rb'<vertex x="([^"]*)" y="([^"]*)"', rb'<vertex y="\2" x="\1"', t))
    mine, theirs = read_3mf_text(swapped), read_3mf(folder / "model.3mf")
    assert all(np.array_equal(mine[k][0], theirs[k][0]) for k in theirs)     # read by the tree reader
    with pytest.raises(ExportError, match="not well-formed XML"):
        read_3mf_text(rezip_3mf(folder / "model.3mf", tmp_path / "b.3mf", lambda t: t.replace(b"</mesh>", b"", 1)))
    with pytest.raises(ExportError, match="triangle index beyond"):
        read_3mf_text(rezip_3mf(folder / "model.3mf", tmp_path / "c.3mf",
                             lambda t: re.sub(rb'v1="\d+"', b'v1="99"', t, count=1)))


def test_batched_solids_equal_one_at_a_time(folder):
    objects = read_3mf_text(folder / "model.3mf")
    batch = solids_of(objects)
    for name, (V, T) in objects.items():
        one, b = Solid(name, V, T), batch[name]
        assert one.convex == b.convex and one.area == pytest.approx(b.area, rel=1e-12)
        assert np.allclose(one.normals, b.normals, atol=1e-12) and np.allclose(one.offsets, b.offsets)


def test_welding_all_parts_at_once_keeps_parts_apart():
    tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 0, 0], [-0.0, 0, 0], [0, 0, 1]]], dtype=np.float32)
    P = np.concatenate([tri, tri])                       # two parts with the same corners
    V, T = _weld_parts(P, np.array([2, 2]))
    assert len(V) == 8 and T.max() == 7                  # 4 distinct corners per part (-0 is 0), parts apart
    assert np.array_equal(V[T[:2]], tri) and np.array_equal(V[T[2:]], tri)


def test_outline_areas_at_once_equal_polygon_measures():
    rng = np.random.default_rng(1)
    polys = [rng.uniform(-5e4, 5e4, (k, 2)) for k in (3, 4, 7, 4)]
    assert np.array_equal(outline_areas(polys), [polygon_measures(Q)[0] for Q in polys])


@pytest.mark.parametrize("lift, fails", [(2e-3, True), (1e-4, False)])
def test_bearing_a_panel_lifted_off_its_beams(tmp_path, lift, fails):
    """A panel lifted by twice the tolerance fails, by a tenth of it passes (manifold3d min_gap decides
    when no witness point lies in the beam)."""
    parts = dome_parts(6, 3)
    g = parts.groups[0]
    lifted = dataclasses.replace(g, vertices=g.vertices + lift * g.normals[:, 1:2, :])
    moved = dataclasses.replace(parts, groups=(lifted,) + parts.groups[1:])
    write_3mf(moved, tmp_path / "model.3mf")
    write_bom(moved, tmp_path / "bom.csv")
    c = check_outputs(tmp_path)["checks"]["bearing"]
    assert c["pass"] is (not fails)
    assert c["min_gap_pairs"] > 0 and (c["max_gap_mm"] > 1e-3) is fails


def test_svg_without_a_group_or_not_xml_fails(folder, tmp_path):
    import shutil

    bad = tmp_path / "svg"
    shutil.copytree(folder, bad)
    text = (bad / "outlines.svg").read_text()
    (bad / "outlines.svg").write_text(text.replace('<g id="P0001"', '<g id="X0001"', 1))
    c = check_outputs(bad)["checks"]["svg"]
    assert c["pass"] is False and c["missing"] == ["P0001"]
    (bad / "outlines.svg").write_text(text.replace("</g>", "", 1))
    assert "not well-formed" in check_outputs(bad)["checks"]["svg"]["error"]


def test_dxf_reader_reads_crlf_the_same_and_refuses_a_bad_group_code(folder, tmp_path):
    from fabricate.export.dxf_text import read_outlines_text

    mine, facts = read_outlines_text(folder / "outlines.dxf")
    raw = (folder / "outlines.dxf").read_bytes()
    (tmp_path / "crlf.dxf").write_bytes(raw.replace(b"\n", b"\r\n"))
    theirs, tf = read_outlines_text(tmp_path / "crlf.dxf")
    assert tf == facts and list(theirs) == list(mine) and all(np.array_equal(mine[k], theirs[k]) for k in mine)
    (tmp_path / "bad.dxf").write_bytes(raw.replace(b"\n 10\n", b"\n1x\n", 1))
    with pytest.raises(ExportError, match="group code is not an integer"):
        read_outlines_text(tmp_path / "bad.dxf")


def test_a_3mf_that_unpacks_to_far_more_than_its_size_is_refused_unread(folder, tmp_path, capsys):
    """A deflated run of one byte unpacks to 1,000 times its size: 20 MB of it would be 20 GB in memory.
    Both readers refuse a model beyond MAX_UNPACK times the file before reading it; the check says so."""
    import shutil
    import zipfile

    from fabricate.app.cli import main
    from fabricate.export import threemf_text

    d = tmp_path / "run"
    shutil.copytree(folder, d)
    with zipfile.ZipFile(folder / "model.3mf") as z:
        names = {n: z.read(n) for n in z.namelist()}
    model = names[threemf_text.MODEL]
    names[threemf_text.MODEL] = model + b" " * (threemf_text.UNPACK_FLOOR + 200 * len(model))  # XML may end in spaces
    with zipfile.ZipFile(d / "model.3mf", "w", zipfile.ZIP_DEFLATED) as z:
        for n, data in names.items():
            z.writestr(n, data)
    size = (d / "model.3mf").stat().st_size
    assert size < 2 * len(model)               # the spaces cost next to nothing packed
    for read in (read_3mf, read_3mf_text):
        with pytest.raises(ExportError, match=r"model.3mf: 3D/3dmodel.model unpacks to \d+ MiB from a"):
            read(d / "model.3mf")
    assert main(["check", str(d)]) == 4
    out = capsys.readouterr()
    assert "internal error" not in out.err and "FAIL 3mf" in out.out and "unpacks to" in out.out
