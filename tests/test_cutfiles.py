"""Cut files per material and thickness nested on stock sheets; the layout plan; one STL per part."""
import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.app.config import NestingSection
from fabricate.export import write_cut_files, write_layout_plan, write_stl_parts
from fabricate.export.dxf import read_outlines
from fabricate.export.stl import read_stl


@pytest.fixture(scope="module")
def parts():
    return build_parts(dome_structure(n_around=6, k=3), PartSpec(glass_thickness=8.0))


@pytest.fixture(scope="module")
def cut(parts, tmp_path_factory):
    out = tmp_path_factory.mktemp("cut")
    return out, write_cut_files(parts, out, NestingSection().model_dump())


def test_one_nested_file_per_material_and_thickness(parts, cut):
    out, facts = cut
    assert sorted(facts) == ["cut_glass_8mm.dxf", "cut_glass_8mm.svg", "cut_steel_60mm.dxf", "cut_steel_60mm.svg"]
    glass, _ = read_outlines(out / "cut_glass_8mm.dxf")
    steel, info = read_outlines(out / "cut_steel_60mm.dxf")
    big = facts["cut_glass_8mm.dxf"]["oversize"]  # this dome's largest panels exceed a jumbo sheet
    assert sorted(list(glass) + big) == sorted(p.id for p in parts.panels) and len(glass) > 0
    assert sorted(steel) == sorted(b.id for b in parts.beams)
    assert info["audit_errors"] == 0 and info["units"] == 4
    lay = facts["cut_steel_60mm.dxf"]["layout"]
    assert lay["sheet_mm"] == [12000.0, 2500.0] and lay["kerf_mm"] == 3.0 and lay["margin_mm"] == 10.0
    assert [s["id"] for s in lay["per_sheet"]][0] == "STEEL-60-S01"
    assert sum(s["parts"] for s in lay["per_sheet"]) == len(parts.beams)
    assert all(0 < s["yield"] <= 1 for s in lay["per_sheet"])
    # every outline lies on its sheet, inside the margin, and the DXF keeps each outline's edge lengths
    W, H = lay["sheet_mm"]
    step = W + 0.1 * W
    for pid, Q in steel.items():
        x = Q[:, 0] - np.floor(Q[:, 0].min() / step) * step
        assert x.min() >= 10 - 1e-6 and x.max() <= W - 10 + 1e-6 and Q[:, 1].min() >= 10 - 1e-6
        F = parts.by_id[pid].flat
        np.testing.assert_allclose(np.linalg.norm(np.roll(Q, -1, 0) - Q, axis=1),
                                   np.linalg.norm(np.roll(F, -1, 0) - F, axis=1), atol=1e-9)


def test_hub_caps_are_nested_with_the_plates_of_their_thickness(tmp_path):
    """The quickstart's parts: T beams with 12 mm flanges, tube hubs with 12 mm caps: one 12 mm steel
    cut file holds the flanges and the caps (their true outline, id and orientation mark); no tube."""
    spec = PartSpec(beam={"section": "tee", "web_mm": 10, "flange_mm": 12, "flange_width_mm": 100},
                    node={"connection": "hub", "hub": "tube", "radius_mm": 80.0, "wall_mm": 8.0, "cap_mm": 12.0})
    parts = build_parts(dome_structure(n_around=6, k=3), spec)
    facts = write_cut_files(parts, tmp_path, NestingSection().model_dump())
    assert sorted(f for f in facts if f.endswith(".dxf")) == ["cut_glass_10mm.dxf", "cut_steel_10mm.dxf",
                                                               "cut_steel_12mm.dxf"]
    steel, info = read_outlines(tmp_path / "cut_steel_12mm.dxf")
    caps = {i for g in parts.of_kind("node") if g.member in ("top cap", "bottom cap") for i in g.ids}
    flanges = {i for g in parts.of_kind("beam") if "flange" in g.member for i in g.ids}
    assert caps and set(steel) == caps | flanges and info["texts"] == len(caps | flanges)
    web, _ = read_outlines(tmp_path / "cut_steel_10mm.dxf")
    assert not set(web) & caps
    for pid in sorted(caps)[:6]:  # the cap drawn is the 24-gon of radius 80 (edge 2 r sin(pi / 24))
        Q = steel[pid]
        np.testing.assert_allclose(np.linalg.norm(np.roll(Q, -1, 0) - Q, axis=1), 160 * np.sin(np.pi / 24),
                                   rtol=1e-9)
    lay = facts["cut_steel_12mm.dxf"]["layout"]
    assert sum(s["parts"] for s in lay["per_sheet"]) == len(caps | flanges)
    svg = (tmp_path / "cut_steel_12mm.svg").read_text()
    assert all(f'id="{i}"' in svg for i in caps)


def test_a_part_larger_than_the_sheet_is_listed_not_nested(parts, tmp_path):
    nest = NestingSection().model_dump()
    nest["steel"]["sheet_mm"] = (3000.0, 2500.0)
    facts = write_cut_files(parts, tmp_path, nest)
    big = facts["cut_steel_60mm.dxf"]["oversize"]
    assert big and all(parts.by_id[i].rect[0] + 20 > 3000 for i in big)
    steel, _ = read_outlines(tmp_path / "cut_steel_60mm.dxf")
    assert not set(big) & set(steel) and len(steel) + len(big) == len(parts.beams)


def test_layout_plan_names_every_part_where_it_sits(parts, tmp_path):
    import ezdxf

    write_layout_plan(parts, tmp_path / "plan.dxf")
    doc = ezdxf.readfile(str(tmp_path / "plan.dxf"))
    assert not doc.audit().has_errors
    texts = {t.dxf.text: np.array(t.dxf.align_point)[:2] for t in doc.modelspace().query("TEXT")}
    assert set(texts) == {p.id for p in parts.panels + parts.beams}
    for p in parts.panels:  # the id sits at the panel's centre in plan
        np.testing.assert_allclose(texts[p.id], p.vertices[list(p.group.ring)][:, :2].mean(axis=0), atol=1e-6)


def test_one_stl_per_part_stays_one_piece_when_welded(parts, tmp_path):
    import manifold3d

    facts = write_stl_parts(parts, tmp_path / "stl")
    assert facts["files"] == len(parts)
    for p in list(parts)[::7]:  # a sample: weld each file by coordinates, it is one closed solid
        P, head = read_stl(tmp_path / "stl" / f"{p.id}.stl")
        V, T = np.unique(P.reshape(-1, 3), axis=0, return_inverse=True)
        m = manifold3d.Manifold(manifold3d.Mesh(vert_properties=V.astype(np.float32),
                                                tri_verts=T.reshape(-1, 3).astype(np.uint32)))
        assert m.status().name == "NoError" and m.genus() == 0
        assert m.volume() == pytest.approx(p.volume_mm3, rel=1e-5) and head["parts"] == 1


def test_to_build123d_is_a_labelled_assembly_of_the_exact_solids(parts):
    model = parts.to_build123d()
    assert model.label == "model" and [c.label for c in model.children] == ["panels", "beams"]
    by_label = {s.label: s for c in model.children for s in c.children}
    assert set(by_label) == {p.id for p in parts}
    for p in list(parts)[::9]:
        s = by_label[p.id]
        assert s.is_valid and s.volume == pytest.approx(p.volume_mm3, rel=1e-9)


def test_a_layout_is_made_once_per_parts_and_arguments(parts):
    """The DXF and the SVG share one layout of the same parts (rectpack runs once); it is the layout a
    fresh computation gives, read-only; other arguments or other parts get their own."""
    from fabricate.export import nesting

    lay = nesting.layout(parts)
    assert nesting.layout(parts, None, 10.0) is lay
    fresh = nesting._layout(parts, None, 10.0, None, True, ("panel", "beam"), None, "S")
    for name in ("group", "index", "sheet", "x", "y", "rotated", "utilisation"):
        assert np.array_equal(getattr(lay, name), getattr(fresh, name))
        with pytest.raises(ValueError):
            getattr(lay, name)[:1] = 0
    assert nesting.layout(parts, spacing=20.0) is not lay
    assert nesting.layout(parts, spacing=20.0).x.min() == pytest.approx(20.0)
    assert nesting.layout(build_parts(dome_structure(n_around=6, k=3), PartSpec(glass_thickness=8.0))) is not lay


@pytest.mark.parametrize("numpy_from", [0, 48, 10**9])
@pytest.mark.parametrize("bin_algo", ["BFF", "BNF"])
@pytest.mark.parametrize("rotation", [True, False])
def test_faster_guillotine_places_every_rectangle_where_rectpack_does(bin_algo, rotation, numpy_from, monkeypatch):
    """Seeded random rectangles (many of equal sizes: ties and merged free sections) on sheets and on
    a strip: the placements of :mod:`fabricate.export.guillotine` are rectpack's own, rectangle by
    rectangle, with its numpy loops always, from 48 free sections on (the default) and never."""
    import rectpack

    from fabricate.export import guillotine
    from fabricate.export.guillotine import GuillotineBssfSas

    monkeypatch.setattr(guillotine, "NUMPY_FROM", numpy_from)

    rng = np.random.default_rng(7)
    sizes = np.concatenate([rng.integers(5, 400, (300, 2)), np.repeat([[100, 40], [40, 100], [250, 250]], 40, 0)])
    for bins in ([(1000, 600, float("inf"))], [(5000, 100000, 1)]):
        placed = []
        for algo in (rectpack.GuillotineBssfSas, GuillotineBssfSas):
            packer = rectpack.newPacker(mode=rectpack.PackingMode.Offline, rotation=rotation, pack_algo=algo,
                                        sort_algo=rectpack.SORT_AREA, bin_algo=getattr(rectpack.PackingBin, bin_algo))
            for i, (w, h) in enumerate(sizes.tolist()):
                packer.add_rect(w, h, rid=i)
            for W, H, count in bins:
                packer.add_bin(W, H, count=count)
            packer.pack()
            placed.append(sorted(packer.rect_list(), key=lambda r: r[5]))
        assert len(placed[0]) == len(sizes) and placed[1] == placed[0]


def test_layouts_of_the_parts_are_rectpacks(parts):
    import rectpack

    from fabricate.export import nesting

    for args in ((None, 10.0, None, True, ("panel", "beam"), None, "S"),
                 ((12000.0, 2500.0), 10.0, 3.0, True, ("beam",), None, "B"),
                 ((12000.0, 2500.0), 10.0, 3.0, False, ("beam",), None, "B")):
        ours, theirs = nesting._layout(parts, *args), nesting._layout(parts, *args, algo=rectpack.GuillotineBssfSas)
        assert ours.sheets == theirs.sheets and ours.size == theirs.size
        for name in ("sheet", "x", "y", "rotated", "utilisation"):
            assert np.array_equal(getattr(ours, name), getattr(theirs, name))


@pytest.mark.parametrize("kept", [0, 8, 64])
@pytest.mark.parametrize("next_fit", [False, True])
@pytest.mark.parametrize("rotation", [True, False])
def test_fast_bin_first_fit_places_every_rectangle_where_rectpack_does(rotation, next_fit, kept, monkeypatch):
    """Seeded random rectangles of several size ranges (ties of equal areas, squares, strips) on bins
    that take a few, dozens or one of them (hundreds of open bins), and on a strip: :func:`nesting.pack`
    (bins skipped by their free sections, ``kept`` of them per bin) puts every rectangle on the bin and
    at the place rectpack's own packer and guillotine class do; a rectangle larger than the bin stays
    unplaced as in rectpack."""
    import rectpack

    from fabricate.export import nesting

    monkeypatch.setattr(nesting, "SECTIONS_KEPT", kept)
    rng = np.random.default_rng(11)
    cases = [(rng.integers(5, 400, (400, 2)), 1000, 600),
             (np.concatenate([rng.integers(200, 700, (300, 2)), np.repeat([[300, 500], [500, 300]], 30, 0)]),
              1000, 800),                                                  # one to four per bin
             (rng.integers(1, 60, (600, 2)) * [1, 8], 900, 500),          # strips, turned or not
             (rng.integers(20, 90, (500, 2)), 3000, 200000),              # one tall strip
             (np.concatenate([rng.integers(50, 300, (100, 2)), [[1200, 90], [90, 1200]]]), 1000, 700)]
    bins = []
    for sizes, bw, bh in cases:
        w, h = sizes[:, 0].astype(np.int64), sizes[:, 1].astype(np.int64)
        ours = nesting.pack(w, h, bw, bh, rotation, next_fit=next_fit)
        theirs = nesting._rectpack(w, h, bw, bh, rotation, next_fit, rectpack.GuillotineBssfSas)
        for a, b in zip(ours, theirs):
            assert np.array_equal(a, b)
        placed = ours[0] >= 0
        assert np.array_equal(placed, ((w <= bw) & (h <= bh)) | (rotation & (h <= bw) & (w <= bh)))
        assert ours[0].max() + 1 >= (w * h)[placed].sum() / (bw * bh)   # no two rectangles overlap
        bins.append(ours[0].max() + 1)
    assert bins[1] > 100 and bins[3] == 1                                 # many open bins; the strip
