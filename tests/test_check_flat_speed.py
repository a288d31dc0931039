"""The batched flat.json and DXF checks give what one part at a time gives, to the last digit, and
still refuse broken files."""
import json

import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.check import _check_dxf, _check_flat
from fabricate.export import flatdata, write_bom, write_dxf, write_step
from fabricate.export.bom import read_bom
from fabricate.export.flatdata import read_flat, rebuild, write_flat
from fabricate.export.step_text import read_step_text
from fabricate.export.verify import match_outline, match_outlines


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A dome with tube hubs (caps of 24 corners, 26 faces) written as STEP, flat.json, DXF and BOM."""
    parts = build_parts(dome_structure(n_around=6, k=3), PartSpec(node={
        "connection": "hub", "hub": "tube", "radius_mm": 80.0, "wall_mm": 8.0, "cap_mm": 12.0}))
    d = tmp_path_factory.mktemp("chk")
    for name, fn in (("model.step", write_step), ("flat.json", write_flat), ("outlines.dxf", write_dxf),
                     ("bom.csv", write_bom)):
        fn(parts, d / name)
    return d


def test_outlines_matched_at_once_equal_one_at_a_time():
    rng = np.random.default_rng(7)
    outlines, faces = [], []
    for t in range(600):
        k = (3, 4, 5, 8, 9, 24)[t % 6]
        F = rng.normal(size=(k, 3)) * rng.choice([1.0, 300.0, 9000.0])
        Q = F[np.roll(np.arange(k), t % k)][:, :2] + rng.normal(size=(k, 2)) * 1e-5
        Q = Q[::-1] if t % 5 == 0 else Q
        Q = np.concatenate([Q, np.zeros((k, 1))], axis=1) if t % 7 == 0 else Q   # a 3D outline
        fs = [F]
        if t % 11 == 0:
            fs = [F[:-1], F]           # two faces: the one of the right corner count is found
        if t % 13 == 0:
            fs = [F[:-1]]              # none of that corner count
        outlines.append(Q)
        faces.append(fs)
    fi, rel, err = match_outlines(outlines, faces)
    for i, (Q, fs) in enumerate(zip(outlines, faces)):
        assert (int(fi[i]), float(rel[i]), float(err[i])) == match_outline(Q, fs)
    assert (fi == -1).any() and (fi == 1).any() and np.isfinite(err[fi >= 0]).all()


def test_corners_of_a_group_at_once_are_the_step_face_loops_and_give_the_same_hausdorff(files):
    solids, _ = read_step_text(files / "model.step")
    groups = read_flat(files / "flat.json")
    assert any(len(g["faces"]) > 6 for g in groups)            # the caps: more faces than a plate
    for g in groups:
        ids = g["ids"]
        expected = {p: None for p in ids[1:]}                   # the first part is not compared
        corners = flatdata._corner_sets(ids, expected, "step", solids, None)
        assert corners[0] is None and hasattr(corners, "buckets")
        X = rebuild(g)
        hd = flatdata._hausdorff_all(X, corners)
        plain = flatdata._hausdorff_all(X, list(corners))               # no buckets: stacked from the list
        for i, pid in enumerate(ids[1:], start=1):
            B = flatdata._step_points(solids[pid])
            np.testing.assert_array_equal(corners[i], B)
            D = np.linalg.norm(X[i][:, None, :] - B[None, :, :], axis=2)
            assert hd[i] == plain[i] == float(max(D.min(axis=1).max(), D.min(axis=0).max()))
            assert hd[i] == flatdata._hausdorff(X[i], np.unique(B, axis=0))


def test_a_bucket_whose_repeats_differ_between_parts_keeps_every_corner():
    rng = np.random.default_rng(3)
    X = rng.normal(size=(2, 8, 3)) * 50
    B0 = X[0][[0, 1, 2, 3, 4, 5, 6, 7, 0, 1]]                  # repeats in the first part only
    B1 = X[1][[0, 1, 2, 3, 4, 5, 6, 7, 2, 3]] + 1e-3
    B1[8] += 5.0                                                # a far point: it decides part 1's figure
    got = flatdata._hausdorff_all(X, [B0, B1])
    assert got == [flatdata._hausdorff(X[0], B0), flatdata._hausdorff(X[1], B1)] and got[1] > 1.0


def test_broken_flat_json_and_dxf_still_fail(files, tmp_path):
    solids, _ = read_step_text(files / "model.step")
    bom = read_bom(files / "bom.csv")
    read = {"step": solids}
    assert _check_flat(files / "flat.json", bom, read)["pass"]
    assert _check_dxf(files / "outlines.dxf", bom, files / "flat.json", "text")["pass"]
    doc = json.loads((files / "flat.json").read_text())
    g = doc["groups"][-1]
    g["outline"][1][0][0] += 0.5                                 # a corner of one outline 0.5 mm off
    g["bevel_reference"][2][0][0] += 0.5
    (tmp_path / "flat.json").write_text(json.dumps(doc))
    res = _check_flat(tmp_path / "flat.json", bom, read)
    assert not res["pass"] and res["failures"][0]["id"] == g["ids"][2] and res["hausdorff_mm_max"] > 0.1
    res = _check_dxf(files / "outlines.dxf", bom, tmp_path / "flat.json", "text")
    assert not res["pass"] and [f["id"] for f in res["failures"]] == [g["ids"][1]]
    (tmp_path / "bad.json").write_text((files / "flat.json").read_text()[:-10])
    with pytest.raises(Exception, match="not a readable flat data file"):
        _check_flat(tmp_path / "bad.json", bom, read)


def test_a_part_without_a_bom_row_is_reported_where_it_is(files):
    solids, _ = read_step_text(files / "model.step")
    bom = read_bom(files / "bom.csv")
    g = read_flat(files / "flat.json")[1]
    gone = g["ids"][3]
    rest = [r for r in bom if r["id"] != gone]
    res = _check_flat(files / "flat.json", rest, {"step": solids})
    assert not res["pass"] and res["failures"] == [{"id": gone, "error": "no BOM row of that id"}]
    assert res["parts"] == res["expected"] + 1 and res["worst"] != gone
    res = _check_dxf(files / "outlines.dxf", rest, files / "flat.json", "text")
    assert not res["pass"] and res["failures"] == [{"id": gone, "error": "no BOM row of that id"}]


def test_a_part_whose_figures_are_not_numbers_fails(files, tmp_path):
    """A NaN in a part's flat data gives a NaN volume error or distance: that part fails (NaN > tol is
    false, so a plain comparison would pass it)."""
    solids, _ = read_step_text(files / "model.step")
    bom = read_bom(files / "bom.csv")
    doc = json.loads((files / "flat.json").read_text())
    g = doc["groups"][0]
    g["bevel_reference"][0][0][0] = float("nan")               # the solid rebuilt from it: NaN figures
    g["outline"][1][0][0] = float("nan")                       # the outline the DXF's must match
    (tmp_path / "flat.json").write_text(json.dumps(doc))
    res = _check_flat(tmp_path / "flat.json", bom, {"step": solids})
    assert not res["pass"] and g["ids"][0] in [f["id"] for f in res["failures"]]
    res = _check_dxf(files / "outlines.dxf", bom, tmp_path / "flat.json", "text")
    assert not res["pass"] and g["ids"][1] in [f["id"] for f in res["failures"]]


@pytest.mark.parametrize("key, edit, expected", [
    ("outline", lambda g: g["outline"][0].pop(), "key 'outline'"),                 # a ragged array
    ("transform", lambda g: g.__setitem__("transform", "x"), "key 'transform'"),
    ("cuts", lambda g: g["cuts"][0].__setitem__(0, 99), "key 'cuts'"),            # no such face
    ("faces", lambda g: g["faces"][0].__setitem__(0, -1), "key 'faces'"),
    ("reference_corners", lambda g: g["reference_corners"].append(10 ** 6), "key 'reference_corners'"),
    ("ids", lambda g: g.pop("ids"), "key 'ids'"),
    ("top_face", lambda g: g.__setitem__("top_face", 1.5), "key 'top_face'"),
])
def test_a_flat_json_of_the_wrong_layout_is_refused_naming_group_and_key(files, tmp_path, key, edit, expected):
    """A tampered flat.json (a ragged or mis-shaped array, an index out of range, a missing key) is a
    failed check naming the group and the key, never an internal error."""
    doc = json.loads((files / "flat.json").read_text())
    edit(doc["groups"][1])
    (tmp_path / "flat.json").write_text(json.dumps(doc))
    with pytest.raises(flatdata.ExportError, match=f"flat.json: group 2 {expected}: .*; expected "):
        read_flat(tmp_path / "flat.json")
    bom = read_bom(files / "bom.csv")
    res = _check_flat_result(tmp_path, bom)
    assert res["pass"] is False and "group 2" in res["error"]


def _check_flat_result(folder, bom):
    from fabricate.check import _one_check

    paths = {"flat": folder / "flat.json"}
    return _one_check("flat", "flat", None, lambda: (_check_flat(paths["flat"], bom, {}), None), paths,
                      frozenset(), {}, {})
