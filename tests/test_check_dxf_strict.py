"""``fabricate check`` (full and ``--fast``) reads every DXF value as strictly as ezdxf's loader: corruption
outside the CUT outlines (a TEXT coordinate that is not a number, an ETCH vertex that is not finite) and
an outline vertex without its y, in ``outlines.dxf`` or a cut file, fail the DXF or cut row with the file,
the line and the value: exit 4, never an internal error."""
import re
import shutil

import pytest
from test_check_runfolder import _rows_of, build_run

from fabricate.app.cli import main


def set_value(text: bytes, layer: bytes, kind: bytes, code: bytes, new: bytes, n: int = 0) -> bytes:
    """``text`` with the value of group ``code`` in the ``n``-th ``kind`` entity on ``layer`` set to ``new``."""
    within = rb"(?:(?!\n  0\n).)*?"                                   # inside one entity
    pattern = (rb"\n  0\n" + kind + rb"\n" + within + rb"\n  8\n" + layer + rb"\n" + within + rb"\n" + code
               + rb"\n([^\n]*)\n")
    m = list(re.finditer(pattern, text, re.S))[n]
    return text[:m.start(1)] + new + text[m.end(1):]


def drop_y(text: bytes) -> bytes:
    """The first CUT outline's first vertex without its y (its ``20`` pair)."""
    at = text.index(b"\n  8\nCUT\n")
    y = text.index(b"\n 20\n", at)
    return text[:y] + text[text.index(b"\n", y + 5):]


def extra_y(text: bytes) -> bytes:
    """The first CUT outline with a y (a ``20`` pair) more than it has x: ezdxf reads it, the outline is lost."""
    at = text.index(b"\n  8\nCUT\n")
    y = text.index(b"\n 20\n", at)
    end = text.index(b"\n", y + 5)
    return text[:end] + text[y:end] + text[end:]


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    return build_run(tmp_path_factory.mktemp("dxfstrict"))


def _edited(run_dir, tmp_path, name, change):
    d = tmp_path / "out"
    shutil.copytree(run_dir, d)
    raw = (d / name).read_bytes()
    new = change(raw)
    assert new != raw
    (d / name).write_bytes(new)
    return d, new


CASES = {
    "text x": ("outlines.dxf", lambda t: set_value(t, b"ETCH", b"TEXT", b" 10", b"abc"), "'abc' (group code 10)",
               "dxf"),
    "etch inf": ("outlines.dxf", lambda t: set_value(t, b"ETCH", b"LWPOLYLINE", b" 10", b"inf"),
                 "'inf' (group code 10)", "dxf"),
    "outline y": ("outlines.dxf", drop_y, "not by its y (group code 20)", "dxf"),
    "cut y": ("cut_steel_60mm.dxf", drop_y, "not by its y (group code 20)", "cut"),
    "outline extra y": ("outlines.dxf", extra_y, "outline vertices without both coordinates", "dxf"),
    "cut extra y": ("cut_steel_60mm.dxf", extra_y, "outline vertices without both coordinates", "cut"),
    "cut text": ("cut_glass_10mm.dxf", lambda t: set_value(t, b"SHEET", b"TEXT", b" 20", b"1e999"),
                 "'1e999' (group code 20)", "cut"),
}


@pytest.mark.parametrize("fast", [False, True], ids=["full", "fast"])
@pytest.mark.parametrize("case", CASES)
def test_a_dxf_value_ezdxf_refuses_fails_its_row(run_dir, tmp_path, capsys, case, fast):
    name, change, words, row = CASES[case]
    d, new = _edited(run_dir, tmp_path, name, change)
    assert main(["check", str(d)] + (["--fast"] if fast else [])) == 4
    out = capsys.readouterr()
    assert "internal error" not in out.err and "Traceback" not in out.err and not out.err.strip(), out.err
    line = _rows_of(out.out)[row]
    assert line.startswith("FAIL") and words in line, line
    if "extra" in case:                                      # read, but the outline is not
        return
    assert f"{name}: line " in line, line
    at = int(line.split(f"{name}: line ")[1].split(":")[0])
    assert 0 < at <= new.count(b"\n")


def test_the_areas_of_no_outlines_are_none():
    import numpy as np

    from fabricate.export.verify import outline_areas

    assert outline_areas([]).shape == (0,)
    assert outline_areas([np.zeros((0, 2)), np.array([[0.0, 0], [2, 0], [2, 1]])]).tolist() == [0.0, 1.0]
