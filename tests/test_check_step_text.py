"""The independent STEP text reader of the full check: agrees with OpenCASCADE, catches broken files."""
import re
import shutil

import numpy as np
import pytest
from cad_fixtures import dome_parts

from fabricate.check import check_outputs
from fabricate.export import write_bom, write_step
from fabricate.export.step_text import read_step_text
from optimize.errors import ExportError


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    parts = dome_parts(6, 3)
    folder = tmp_path_factory.mktemp("steptext")
    write_step(parts, folder / "model.step")
    write_bom(parts, folder / "bom.csv")
    return folder, parts


def test_text_reader_agrees_with_opencascade(run_dir):
    from fabricate.export.brep import solid_facts
    from fabricate.export.step_read import read_step

    folder, parts = run_dir
    mine, facts = read_step_text(folder / "model.step")
    occ, occ_facts = read_step(folder / "model.step")
    assert facts["unit_mm"] and facts["complete"] and facts["solids"] == len(parts)
    assert [n for n, _ in occ] == list(mine)
    for name, shape in occ:
        f = solid_facts(shape)
        assert mine[name]["volume_mm3"] == pytest.approx(f["volume_mm3"], rel=1e-9)
        assert mine[name]["colour"] == occ_facts["colours"][name]
    from fabricate.export.verify import face_polygons

    def loop(P):  # a loop from its least corner on, in its turning order (a reader may start anywhere)
        Q = np.round(P, 6).tolist()
        k = Q.index(min(Q))
        return Q[k:] + Q[:k]

    name, shape = occ[0]
    theirs = sorted(loop(P) for P in face_polygons(shape))
    assert sorted(loop(P) for P in mine[name]["faces"]) == theirs  # same loops, same turning


def test_full_check_passes_with_the_text_reader(run_dir):
    folder, parts = run_dir
    step = check_outputs(folder)["checks"]["step"]
    assert step["pass"] and step["read_back"] == "text" and step["solids"] == len(parts)
    assert step["max_off_plane_mm"] < 1e-7 and step["volume_rel_error_max"] < 1e-9


def _broken(run_dir, tmp_path, edit):
    folder, _ = run_dir
    bad = tmp_path / "bad"
    shutil.copytree(folder, bad)
    text = (bad / "model.step").read_text()
    new = edit(text)
    assert new != text
    (bad / "model.step").write_text(new)
    return check_outputs(bad)["checks"]["step"]


def test_a_reversed_edge_breaks_the_shell(run_dir, tmp_path):
    def flip(t):  # the first oriented edge walks the other way: its loop no longer closes
        return re.sub(r"(ORIENTED_EDGE\('',\*,\*,#\d+,\.)([TF])(\.\))",
                      lambda m: m.group(1) + ("F" if m.group(2) == "T" else "T") + m.group(3), t, count=1)
    c = _broken(run_dir, tmp_path, flip)
    assert c["pass"] is False and c["n_invalid"] == 1
    assert any("loops_closed" in k or "closed" in k for k in c["invalid_reasons"])


def test_a_moved_point_is_off_its_plane_and_changes_the_volume(run_dir, tmp_path):
    def move(t):  # the point of the first vertex moves by 0.01 mm
        pid = re.search(r"=VERTEX_POINT\('',#(\d+)\)", t).group(1)
        return re.sub(rf"(#{pid}=CARTESIAN_POINT\('',\()([^,]+)",
                      lambda m: m.group(1) + repr(float(m.group(2)) + 0.01), t, count=1)
    c = _broken(run_dir, tmp_path, move)
    assert c["pass"] is False and c["max_off_plane_mm"] > 1e-3
    assert any("off its plane" in k for k in c["invalid_reasons"])


def test_a_renamed_part_and_a_lost_colour_fail(run_dir, tmp_path):
    c = _broken(run_dir, tmp_path, lambda t: t.replace("PRODUCT('P0001','P0001'", "PRODUCT('X0001','X0001'", 1))
    assert c["pass"] is False and c["missing"] == ["P0001"] and c["unexpected"] == ["X0001"]
    c = _broken(run_dir, tmp_path / "2", lambda t: re.sub(r"#\d+=STYLED_ITEM\([^;]*;\n", "", t, count=1))
    assert c["pass"] is False and len(c["uncoloured"]) == 1


def test_curved_or_foreign_files_are_refused_with_the_reason(tmp_path):
    p = tmp_path / "x.step"
    p.write_text("ISO-10303-21;\nDATA;\n#1=CYLINDRICAL_SURFACE('',#2,5.);\nENDSEC;\nEND-ISO-10303-21;\n")
    with pytest.raises(ExportError, match="planar B-reps only"):
        read_step_text(p)
    p.write_text("solid x\nendsolid x\n")
    with pytest.raises(ExportError, match="not a STEP file"):
        read_step_text(p)


@pytest.fixture(scope="module")
def dxf_file(run_dir):
    from fabricate.export import write_dxf

    folder, parts = run_dir
    write_dxf(parts, folder / "outlines.dxf")
    return folder / "outlines.dxf"


def test_dxf_text_reader_agrees_with_ezdxf(dxf_file):
    from fabricate.export.dxf import read_outlines
    from fabricate.export.dxf_text import read_outlines_text

    mine, facts = read_outlines_text(dxf_file)
    theirs, tf = read_outlines(dxf_file)
    assert set(mine) == set(theirs) and facts["units"] == tf["units"] == 4 and facts["texts"] == tf["texts"]
    assert all(np.array_equal(mine[k], theirs[k]) for k in mine)
    assert facts["lint"] == [] and facts["audit_errors"] == 0


def _same_handle(t: str) -> str:
    """The second outline gets the first one's handle."""
    first, second = re.findall(r"LWPOLYLINE\n  5\n([0-9A-F]+)\n", t)[:2]
    return t.replace(f"LWPOLYLINE\n  5\n{second}\n", f"LWPOLYLINE\n  5\n{first}\n", 1)


@pytest.mark.parametrize("edit, words", [
    (lambda t: t[: t.rindex("EOF")], "end with 0/EOF"),
    (lambda t: re.sub(r"(\nCUT\n100\nAcDbPolyline\n 90\n\d+\n 70\n)1(\n)", r"\g<1>0\2", t, count=1),
     "not closed"),
    (lambda t: _same_handle(t), "duplicate entity handles"),
])
def test_dxf_lint_catches_broken_files(dxf_file, tmp_path, edit, words):
    from fabricate.export.dxf_text import read_outlines_text

    text = dxf_file.read_text()
    bad = tmp_path / "bad.dxf"
    new = edit(text)
    assert new != text
    bad.write_text(new)
    _, facts = read_outlines_text(bad)
    assert any(words in x for x in facts["lint"]), facts["lint"]
