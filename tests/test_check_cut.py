"""``fabricate check`` of the nested cut files: every part once, in the file of its material and
thickness, of its true shape, on a sheet with the margin clear, the kerf kept between parts; a part
too large for the sheet may be left out, no other."""
import re
import shutil

import pytest
from cad_fixtures import dome_structure

from fabricate.app.config import NestingSection
from fabricate.cad import PartSpec, build_parts
from fabricate.check import _check_outputs
from fabricate.export import write_bom, write_cut_files, write_dxf, write_flat


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """Plate beams and 8 mm glass; the largest panels exceed the glass sheet (listed, not nested)."""
    parts = build_parts(dome_structure(n_around=6, k=3), PartSpec(glass_thickness=8.0))
    out = tmp_path_factory.mktemp("cut")
    for name, fn in (("bom.csv", write_bom), ("flat.json", write_flat), ("outlines.dxf", write_dxf)):
        fn(parts, out / name)
    facts = write_cut_files(parts, out, NestingSection().model_dump())
    assert facts["cut_glass_8mm.dxf"]["oversize"]
    return out


def _check(folder):
    return _check_outputs(folder, only=frozenset({"dxf", "cut"}))["checks"]["cut"]


def _copy(run_dir, tmp_path):
    d = tmp_path / "out"
    shutil.copytree(run_dir, d)
    return d


def _cut_outlines(text: str) -> list[re.Match]:
    """The CUT polylines of a DXF text written here, with their id (XDATA)."""
    return list(re.finditer(r"  0\nLWPOLYLINE\n(?:(?!  0\n).)*?  8\nCUT\n.*?1000\n([^\n]+)\n", text, re.S))


def test_the_cut_files_as_written_pass(run_dir):
    c = _check(run_dir)
    assert c["pass"] is True and c["files"] == 2 and c["failed"] == 0 and c["sheets"] >= 2, c


def _edit(run_dir, tmp_path, name, change):
    d = _copy(run_dir, tmp_path)
    text = (d / name).read_text()
    new = change(text)
    assert new != text
    (d / name).write_text(new)
    return _check(d)


def _errors(c) -> str:
    assert c["pass"] is False, c
    return " | ".join(f"{f.get('id')}: {f['error']}" for f in c["failures"])


def test_a_part_moved_onto_another_fails(run_dir, tmp_path):
    def change(text):
        a, b = _cut_outlines(text)[:2]
        xy = re.findall(r" 10\n[^\n]+\n 20\n[^\n]+\n", a.group(0))
        old = re.findall(r" 10\n[^\n]+\n 20\n[^\n]+\n", b.group(0))
        body = b.group(0)
        for o, n in zip(old, xy + xy):
            body = body.replace(o, n, 1)
        return text.replace(b.group(0), body, 1)
    errors = _errors(_edit(run_dir, tmp_path, "cut_steel_60mm.dxf", change))
    assert "less than the 3 mm kerf" in errors and "not the shape of its outline" in errors


def test_a_part_left_out_fails(run_dir, tmp_path):
    pid = []

    def change(text):
        m = _cut_outlines(text)[3]
        pid.append(m.group(1))
        return text.replace(m.group(0), "", 1)
    errors = _errors(_edit(run_dir, tmp_path, "cut_steel_60mm.dxf", change))
    assert f"{pid[0]}: in no cut file; its stock rectangle fits the steel 60 mm sheet" in errors


def test_a_part_in_the_file_of_another_material_fails(run_dir, tmp_path):
    def change(text):
        m = _cut_outlines(text)[0]
        return text.replace(m.group(0), m.group(0).replace(f"1000\n{m.group(1)}\n", "1000\nP0001\n"), 1)
    errors = _errors(_edit(run_dir, tmp_path, "cut_steel_60mm.dxf", change))
    assert "P0001: not a steel part 60 mm thick in the bill of materials" in errors


def test_an_outline_of_another_shape_fails(run_dir, tmp_path):
    def change(text):
        m = _cut_outlines(text)[2]
        x = re.search(r" 10\n([^\n]+)\n", m.group(0))
        body = m.group(0).replace(x.group(0), f" 10\n{float(x.group(1)) + 0.5!r}\n", 1)
        return text.replace(m.group(0), body, 1)
    errors = _errors(_edit(run_dir, tmp_path, "cut_steel_60mm.dxf", change))
    assert "not the shape of its outline in outlines.dxf: 0.5 mm off" in errors


def test_a_part_in_the_margin_and_a_sheet_without_its_label_fail(run_dir, tmp_path):
    def into_margin(text):
        m = _cut_outlines(text)[0]
        xs = [float(v) for v in re.findall(r" 10\n([^\n]+)\n", m.group(0))]
        body = re.sub(r" 10\n([^\n]+)\n", lambda v: f" 10\n{float(v.group(1)) - min(xs) + 2.0!r}\n", m.group(0))
        return text.replace(m.group(0), body, 1)
    errors = _errors(_edit(run_dir, tmp_path, "cut_steel_60mm.dxf", into_margin))
    assert "on no sheet with its 10 mm margin clear" in errors
    c = _edit(run_dir, tmp_path / "b", "cut_steel_60mm.dxf",
              lambda t: re.sub(r"STEEL-60-S01: [^\n]+", "STEEL-60-S01", t, count=1))
    assert "one label per frame" in _errors(c) or "a sheet label without its size" in _errors(c)


def test_a_cut_file_the_run_wrote_and_that_is_gone_fails(run_dir, tmp_path):
    import json

    d = _copy(run_dir, tmp_path)
    (d / "report.json").write_text(json.dumps({"files": {"cut_steel_60mm.dxf": {"bytes": 1}}}))
    (d / "cut_steel_60mm.dxf").unlink()
    errors = _errors(_check(d))
    assert "the run wrote it; it is missing" in errors


def test_a_material_every_part_of_which_is_too_large_has_an_empty_file_and_passes(tmp_path):
    """A glass sheet smaller than every panel: the glass file holds no sheet and no part, and passes;
    without it, the check says the glass has no cut file."""
    parts = build_parts(dome_structure(n_around=6, k=3), PartSpec(glass_thickness=8.0))
    for name, fn in (("bom.csv", write_bom), ("flat.json", write_flat), ("outlines.dxf", write_dxf)):
        fn(parts, tmp_path / name)
    nesting = NestingSection().model_dump()
    nesting["glass"]["sheet_mm"] = (500.0, 400.0)
    facts = write_cut_files(parts, tmp_path, nesting)
    assert len(facts["cut_glass_8mm.dxf"]["oversize"]) == len(parts.panels)
    assert _check(tmp_path)["pass"] is True
    (tmp_path / "cut_glass_8mm.dxf").unlink()
    assert "no cut file for the 12 glass parts 8 mm thick" in _errors(_check(tmp_path))
