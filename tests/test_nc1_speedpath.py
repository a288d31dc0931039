"""The NC1 writer's group-at-once path against its one-part functions (the same text, byte for byte),
and the atomic files it writes with few system calls (mode, temporary names, failure)."""
import os
from types import SimpleNamespace

import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.export import nc1
from fabricate.export.schedules import beam_angles
from optimize.errors import ExportError

TUBE = {"connection": "hub", "hub": "tube", "radius_mm": 90.0, "wall_mm": 8.0, "cap_mm": 12.0}
RHS = {"section": "rhs", "web_mm": 6, "flange_mm": 8, "flange_width_mm": 120}
KW = {"order": "dome", "grade": "S355"}


@pytest.fixture(scope="module")
def rhs_parts():
    return build_parts(dome_structure(n_around=6, k=3), PartSpec(node=TUBE, beam=RHS))


def _plates(rng, p, k):
    """A beam-like group of ``p`` random plates of ``k`` corners, some taller than long (turned), with
    end bevels that tie in magnitude, differ in sign and hold NaN."""
    flat = rng.uniform(-500.0, 3000.0, (p, k, 2)) * rng.uniform(0.01, 1.0, (p, 1, 2))
    bevel = np.round(rng.uniform(-30.0, 30.0, (p, 2, 2)), 1)
    bevel[::4, :, 1] = -bevel[::4, :, 0]                        # |a| == |b|: the first wins
    bevel[1::7, 0, 1] = np.nan
    bevel[2::7, 1, 0] = np.nan
    group = SimpleNamespace(flat=flat, thickness_mm=rng.uniform(4.0, 20.0, p), volume_mm3=rng.uniform(1e5, 1e7, p),
                            area_mm2=rng.uniform(1e4, 1e6, p), ids=tuple(f"B{i:04d}.1" for i in range(p)),
                            element=rng.integers(0, 10000, p), member="web +" if k % 2 else "", kind="beam",
                            neighbours=tuple(tuple(f"P{j:04d}" for j in range(i % 30)) for i in range(p)))
    return group, {"mitre": rng.uniform(-60.0, 60.0, (p, 2)), "end_bevel": bevel}


@pytest.mark.parametrize("k", [3, 4, 5, 8, 9, 13])
def test_group_texts_are_the_one_part_texts_of_random_plates(k):
    rng = np.random.default_rng(k)
    group, angles = _plates(rng, 60, k)
    assert (np.ptp(group.flat[:, :, 1], axis=1) > np.ptp(group.flat[:, :, 0], axis=1)).any()   # some turned
    texts = nc1.nc1_texts(group, density=7850.0, angles=angles, **KW)
    assert len(texts) == 60
    for i, text in enumerate(texts):
        assert text == nc1.nc1_text(group, i, density=7850.0, angles=angles, **KW), group.ids[i]


@pytest.mark.parametrize("k", [8, 24, 31])
def test_group_texts_are_the_one_part_texts_of_random_tubes(k):
    rng = np.random.default_rng(k)
    p = 40
    a = np.linspace(0.0, 2 * np.pi, k, endpoint=False)
    r = rng.uniform(30.0, 200.0, (p, 1))
    ring = np.stack([r * np.cos(a), r * np.sin(a), np.zeros((p, k))], axis=2) + rng.uniform(-1e4, 1e4, (p, 1, 3))
    V = np.concatenate([ring + rng.normal(0, 1e-3, ring.shape), rng.uniform(-1e4, 1e4, (p, 3 * k, 3))], axis=1)
    group = SimpleNamespace(vertices=V, thickness_mm=rng.uniform(3.0, 12.0, p), length_mm=rng.uniform(50, 400, p),
                            volume_mm3=rng.uniform(1e5, 1e7, p), ids=tuple(f"N{i:04d}.1" for i in range(p)),
                            element=np.arange(p), neighbours=tuple((f"B{i:04d}",) * (i % 12) for i in range(p)))
    texts = nc1.nc1_tube_texts(group, density=7850.0, **KW)
    assert texts == [nc1.nc1_tube_text(group, i, density=7850.0, **KW) for i in range(p)]


def test_group_texts_are_the_one_part_texts_of_a_rhs_dome_with_tube_hubs(rhs_parts):
    beams = list(rhs_parts.of_kind("beam"))
    tubes = [g for g in rhs_parts.of_kind("node") if g.member == "tube"]
    assert len(beams) == 6 and len(tubes) == 1
    for g in beams:
        angles = beam_angles(g)
        texts = nc1.nc1_texts(g, density=7850.0, angles=angles, **KW)
        assert texts == [nc1.nc1_text(g, i, density=7850.0, angles=angles, **KW) for i in range(len(g))]
    g = tubes[0]
    assert nc1.nc1_tube_texts(g, density=7850.0, **KW) == [nc1.nc1_tube_text(g, i, density=7850.0, **KW)
                                                           for i in range(len(g))]


def test_files_have_the_umask_mode_and_no_temporary_is_left(rhs_parts, tmp_path):
    old = os.umask(0o027)
    try:
        facts = nc1.write_nc1(rhs_parts, tmp_path / "nc1")
    finally:
        os.umask(old)
    names = os.listdir(tmp_path / "nc1")
    assert len(names) == facts["files"] and all(n.endswith(".nc1") and not n.startswith(".") for n in names)
    assert os.listdir(tmp_path) == ["nc1"]                            # the staging folder is gone
    assert {os.stat(tmp_path / "nc1" / n).st_mode & 0o7777 for n in names} == {0o640}
    first = rhs_parts.of_kind("beam")[0]
    data = (tmp_path / "nc1" / f"{first.ids[0]}.nc1").read_bytes()
    angles = beam_angles(first)
    text = nc1.nc1_text(first, 0, order="roof", grade=rhs_parts.spec.steel_grade,
                        density=rhs_parts.spec.density("beam"), angles=angles)
    assert data == text.replace("\n", "\r\n").encode("ascii") and b"\r\n" in data


def test_the_mode_is_set_where_the_created_one_differs(rhs_parts, tmp_path, monkeypatch):
    """Where the mode ``open`` gives is not 0666 less the umask read (a folder's default ACL; here the
    umask the writer reads made to differ from the process's), every file is given that mode."""
    old = os.umask(0o022)
    try:
        monkeypatch.setattr(nc1, "umask", lambda: 0o077)
        nc1.write_nc1(rhs_parts, tmp_path / "nc1")
    finally:
        os.umask(old)
    assert {os.stat(p).st_mode & 0o7777 for p in (tmp_path / "nc1").iterdir()} == {0o600}


def test_a_file_of_the_temporary_name_is_left_alone(rhs_parts, tmp_path, monkeypatch):
    tokens = iter(["aaaa", "bbbb"])
    monkeypatch.setattr(nc1.secrets, "token_hex", lambda n: next(tokens))
    folder = tmp_path / "nc1"
    folder.mkdir()
    pid = rhs_parts.of_kind("beam")[0].ids[0]
    foreign = folder / f".{pid}.nc1.aaaa.part"
    foreign.write_bytes(b"another writer's")
    facts = nc1.write_nc1(rhs_parts, folder)
    assert foreign.read_bytes() == b"another writer's"
    assert (folder / f"{pid}.nc1").read_bytes().startswith(b"ST\r\n")
    assert sorted(os.listdir(folder)) == sorted([foreign.name] + [f"{p}.nc1" for p in _ids(rhs_parts)])
    assert facts["files"] == len(_ids(rhs_parts))


def _ids(parts):
    ids = [pid for g in parts.of_kind("beam") for pid in g.ids]
    return ids + [pid for g in parts.of_kind("node") if g.member == "tube" for pid in g.ids]


def test_a_failed_file_raises_export_error_and_leaves_no_temporary(rhs_parts, tmp_path):
    folder = tmp_path / "nc1"
    pid = rhs_parts.of_kind("beam")[1].ids[3]
    (folder / f"{pid}.nc1").mkdir(parents=True)                       # a folder where the file goes
    (folder / f"{pid}.nc1" / "x").write_text("x")
    with pytest.raises(ExportError, match="nc1.*cannot write the NC1 files"):
        nc1.write_nc1(rhs_parts, folder)
    assert not [n for n in os.listdir(folder) if n.startswith(".")]


def _dumps(value):
    import json

    return json.dumps(value, separators=(",", ":"))


@pytest.mark.parametrize("shape", [(), (1,), (7,), (5, 3), (4, 6, 2), (3, 4, 4), (0,), (3, 0, 2), (2, 1, 1, 3)])
@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.int64, np.uint8, np.bool_])
def test_json_array_is_the_text_json_writes(shape, dtype):
    from fabricate.export.flatdata import json_array

    rng = np.random.default_rng(len(shape))
    values = np.array([0.0, -0.0, 1.0, -2.5, 1e16, 1e-5, 1e-4, 0.1, 123456.789, 5e-324, 1.7976931348623157e308])
    size = int(np.prod(shape))                          # the special values first, each at least once
    pool = np.concatenate([values, rng.normal(0, 1e3, 64)])
    a = pool[np.arange(size) % 75][rng.permutation(size)].reshape(shape) if shape else np.float64(-0.0)
    if np.dtype(dtype).kind != "f":                     # repeated ints and bools
        a = rng.integers(0, 200, shape) % 7 == 0 if dtype is np.bool_ else rng.integers(-99, 99, shape) % 200
    if dtype is np.float32:
        a = np.clip(a, -3e38, 3e38)                     # finite in float32
    a = np.asarray(a).astype(dtype)
    assert json_array(a) == _dumps(a.tolist())
    if a.dtype.kind == "f" and a.size:
        b = a.copy()
        b.flat[-1] = np.nan
        assert json_array(b) == _dumps(b.tolist()) and "NaN" in json_array(b)
        b.flat[0] = -np.inf
        assert json_array(b) == _dumps(b.tolist()) and "-Infinity" in json_array(b)


def test_json_array_tells_minus_zero_from_zero_and_repeats_values():
    from fabricate.export.flatdata import json_array

    a = np.array([[0.0, -0.0, 0.1], [-0.0, 0.1, 0.0]])
    assert json_array(a) == "[[0.0,-0.0,0.1],[-0.0,0.1,0.0]]" == _dumps(a.tolist())


def test_json_array_of_a_transposed_view_keeps_its_order():
    from fabricate.export.flatdata import json_array

    a = np.arange(24.0).reshape(2, 3, 4) * 0.1
    for b in (a.transpose(2, 0, 1), a[:, ::-1], a[..., ::2]):
        assert json_array(b) == _dumps(b.tolist())


def test_flat_json_is_the_text_json_writes_of_what_it_holds(rhs_parts, tmp_path):
    """The file is the canonical ``json.dumps`` text of its own content (floats as ``repr``, the keys in
    the writer's order), and the content is the parts' arrays."""
    import json

    from fabricate.cad.parts import cut_from_sheet
    from fabricate.export.flatdata import read_flat, write_flat

    facts = write_flat(rhs_parts, tmp_path / "flat.json")
    text = (tmp_path / "flat.json").read_text(encoding="utf-8")
    doc = json.loads(text)
    assert _dumps(doc) == text and facts["bytes"] == len(text)
    groups = [g for g in rhs_parts.groups if cut_from_sheet(g.kind, g.member) and len(g)]
    assert len(groups) == len(doc["groups"]) > 5 and facts["parts"] == sum(len(g) for g in groups)
    for g, read in zip(groups, read_flat(tmp_path / "flat.json")):
        assert read["ids"] == list(g.ids) and read["faces"] == g.faces
        for key, a in (("outline", g.flat), ("transform", g.transform), ("bevel_deg", g.bevel_deg),
                       ("bevel_reference_z_mm", g.bevel_ref_z), ("thickness_mm", g.thickness_mm), ("cuts", g.cuts)):
            assert np.array_equal(read[key], a) and read[key].shape == a.shape, key
    assert not [n for n in os.listdir(tmp_path) if n.startswith(".")]


def _reference_read_nc1(path) -> dict:
    """The NC1 reader as it was before it read the lines by regular expressions (line by line): the
    fast one must read every file the same, and refuse every file it refused with the same message."""
    from fabricate.export.nc1_read import FACES, HEADER, NUMERIC

    blocks = []
    with open(path, encoding="ascii", newline="") as fh:
        text = fh.read()
    for raw in text.splitlines():
        if raw.startswith("**"):
            continue
        if len(raw) >= 2 and raw[:2].isalpha() and raw[:2].isupper() and raw[2:].strip() == "":
            blocks.append((raw[:2], []))
        elif blocks:
            blocks[-1][1].append(raw)
        elif raw.strip():
            raise ValueError(f"{path}: data before the first block: {raw!r}")
    names = [b for b, _ in blocks]
    if names[:1] != ["ST"] or names[-1:] != ["EN"]:
        raise ValueError(f"{path}: expected ST ... EN, found {names}")
    st = blocks[0][1]
    if len(st) < len(HEADER):
        raise ValueError(f"{path}: ST has {len(st)} lines, expected {len(HEADER)}")
    header = {k: v.strip() for k, v in zip(HEADER, st)}
    for k in NUMERIC:
        header[k] = float(header[k])
    header["quantity"] = int(header["quantity"])
    contours = []
    for name, lines in blocks:
        if name != "AK":
            continue
        face, pts = None, []
        for line in lines:
            tokens = line.split()
            if not tokens:
                continue
            if tokens[0] in FACES:
                face, tokens = tokens[0], tokens[1:]
            pts.append([float(tokens[0].rstrip("uosr")), float(tokens[1])])
        contours.append((face, np.array(pts)))
    return {"header": header, "contours": contours, "blocks": names}


def _outcome(read, path):
    try:
        nc = read(path)
    except (ValueError, IndexError) as exc:
        return type(exc).__name__, str(exc)
    return nc["header"], nc["blocks"], [(f, P.tolist(), P.shape) for f, P in nc["contours"]]


def test_the_reader_reads_mangled_files_as_the_line_by_line_reader(rhs_parts, tmp_path):
    """Written files, their line ends changed ("\\r\\n", "\\n", "\\r", "\\x0b", "\\x1e", mixed), comments,
    blank lines, white space after a keyword, lower-case or foreign keywords, a second contour with
    another face, lines lost or added: the same header, blocks and contours, or the same refusal."""
    from fabricate.export.nc1_read import read_nc1

    nc1.write_nc1(rhs_parts, tmp_path / "nc1")
    files = sorted((tmp_path / "nc1").glob("*.nc1"))
    rng = np.random.default_rng(7)
    extra = ["** a comment", "", "   ", "AK  ", "BO", "SI \t", "st", "A1", "XYZ", "  o 1.0 2.0 0.0", "  3.5s 4 0",
             "  u 7 8", "EN", "ST", "**", "x", "  v", "  1e3 -0 0", "AK\x1f"]
    seen = set()
    for n in range(400):
        lines = files[n % len(files)].read_bytes().decode("ascii").split("\r\n")
        for _ in range(rng.integers(0, 4)):
            op = rng.integers(0, 3)
            j = int(rng.integers(0, len(lines) + 1))
            if op == 0:
                lines.insert(j, extra[rng.integers(0, len(extra))])
            elif op == 1 and j < len(lines):
                del lines[j]
            elif j < len(lines):
                lines[j] = lines[j] + " " * int(rng.integers(1, 3))
        ends = ["\r\n", "\n", "\r", "\x0b", "\x1e"]
        text = "".join(line + (ends[n % 5] if n % 7 else ends[rng.integers(0, 5)]) for line in lines)
        path = tmp_path / f"m{n}.nc1"
        path.write_bytes(text.encode("ascii"))
        new, old = _outcome(read_nc1, path), _outcome(_reference_read_nc1, path)
        if old[0] == "IndexError":                     # a contour line with no x y: now a ValueError
            assert new[0] == "ValueError" and "expected x y" in new[1], new
        else:
            assert new == old, (n, text)
        seen.add(old[0] if isinstance(old[0], str) else "read")
    assert {"read", "ValueError"} <= seen                                   # both outcomes were met


def test_a_new_folder_is_put_in_place_whole_and_not_at_all_on_failure(rhs_parts, tmp_path, monkeypatch):
    """Into a new folder the files are written in a staging folder beside it, published when all are
    written: the same files as written one by one into a folder that holds a file already; a failure
    half-way leaves no nc1/ and no staging folder, and the folder of files is kept as it was."""
    fresh, kept = tmp_path / "fresh" / "nc1", tmp_path / "kept" / "nc1"
    kept.mkdir(parents=True)
    (kept / "mine.txt").write_text("a user's note")
    a, b = nc1.write_nc1(rhs_parts, fresh), nc1.write_nc1(rhs_parts, kept)
    assert a["files"] == b["files"] == len(_ids(rhs_parts)) and a["bytes"] == b["bytes"]
    assert sorted(os.listdir(kept)) == sorted(os.listdir(fresh) + ["mine.txt"])
    assert all((fresh / n).read_bytes() == (kept / n).read_bytes() for n in os.listdir(fresh))
    real, calls = nc1._Files.write, []

    def failing(self, name, data):
        calls.append(name)
        if len(calls) == 7:
            raise OSError(28, "No space left on device")
        return real(self, name, data)

    monkeypatch.setattr(nc1._Files, "write", failing)
    with pytest.raises(ExportError, match="cannot write the NC1 files .No space left on device"):
        nc1.write_nc1(rhs_parts, tmp_path / "failed" / "nc1")
    assert os.listdir(tmp_path / "failed") == []
    calls.clear()
    with pytest.raises(ExportError):
        nc1.write_nc1(rhs_parts, kept)
    assert (kept / "mine.txt").read_text() == "a user's note" and len(os.listdir(kept)) == len(_ids(rhs_parts)) + 1
