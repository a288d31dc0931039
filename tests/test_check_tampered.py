"""``fabricate check`` on files changed after the run: a bill of materials that is not one fails the
check at once (exit 4, one line naming the line and column), an IFC file that does not parse fails
its check (exit 4) -- never an internal error (exit 1) with a traceback."""
import shutil

import pytest
from cad_fixtures import dome_structure

from fabricate.app.cli import main
from fabricate.cad import PartSpec, build_parts
from fabricate.check_fast import run_check
from fabricate.export import write_bom, write_ifc, write_step
from fabricate.export.bom import read_bom
from optimize.errors import ExportError


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    parts = build_parts(dome_structure(n_around=6, k=3), PartSpec())
    folder = tmp_path_factory.mktemp("run")
    for name, fn in (("model.step", write_step), ("bom.csv", write_bom), ("model.ifc", write_ifc)):
        fn(parts, folder / name)
    return folder


def _with(run_dir, tmp_path, name, edit):
    d = tmp_path / "out"
    shutil.copytree(run_dir, d)
    (d / name).write_bytes(edit((d / name).read_bytes()))
    return d


def _cell(line: int, col: int, value: bytes):
    def edit(data: bytes) -> bytes:
        rows = data.split(b"\r\n" if b"\r\n" in data else b"\n")
        cells = rows[line - 1].split(b",")
        cells[col] = value
        rows[line - 1] = b",".join(cells)
        return b"\n".join(rows)
    return edit


@pytest.mark.parametrize("edit, words", [
    (_cell(3, 7, b"12.5e"), "line 3 column volume_mm3: '12.5e'; expected a finite number"),
    (_cell(4, 4, b"nan"), "line 4 column area_m2: 'nan'; expected a finite number"),
    (_cell(2, 2, b"x"), "line 2 column element: 'x'; expected a finite number"),
    (_cell(3, 16, b"steel,extra"), "line 3 has 18 fields, expected 17"),
    (lambda d: d[:-30], "fields, expected 17"),                        # the last row cut short
    (lambda d: d[:200] + b"\xff\xfe" + d[200:], "not a bill of materials in CSV"),
])
def test_a_bom_that_is_not_one_fails_in_one_line(run_dir, tmp_path, capsys, edit, words):
    d = _with(run_dir, tmp_path, "bom.csv", edit)
    with pytest.raises(ExportError, match="bom.csv: "):
        read_bom(d / "bom.csv")
    assert main(["check", str(d)]) == 4
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bom.csv" in err[0] and words in err[0] and "Traceback" not in err[0], err


def _broken_line(d: bytes) -> bytes:
    """Text that does not parse inserted into a face's index list past the first quarter of the file
    (inside a string literal it would be the string's content, and ifcopenshell reads some broken
    texts between entities without an error)."""
    key = b"IFCINDEXEDPOLYGONALFACE(("
    i = d.index(key, len(d) // 4) + len(key) + 1
    return d[:i] + b"#9=IFCWALL((;\n" + d[i:]


@pytest.mark.parametrize("edit", [_broken_line,
                                  lambda d: b"", lambda d: b"ISO-10303-21;\nnot a header\n"])
def test_an_ifc_file_that_does_not_parse_fails_its_check(run_dir, tmp_path, capsys, edit):
    d = _with(run_dir, tmp_path, "model.ifc", edit)
    c = run_check(d, "full")["checks"]["ifc"]
    assert c["pass"] is False and "model.ifc: not a readable IFC file" in c["error"]
    assert main(["check", str(d)]) == 4
    out = capsys.readouterr()
    assert "internal error" not in out.err and "FAIL ifc" in out.out


def test_a_3mf_whose_packed_model_is_damaged_fails_its_check(tmp_path, capsys):
    """Bytes of the deflated model changed: the 3MF reader says the file does not read (a zlib error was an
    internal error); the check's 3mf row fails, exit 4."""
    from fabricate.export import write_3mf
    from fabricate.export.threemf_text import read_3mf_text

    parts = build_parts(dome_structure(n_around=6, k=3), PartSpec())
    write_3mf(parts, tmp_path / "model.3mf")
    write_bom(parts, tmp_path / "bom.csv")
    raw = (tmp_path / "model.3mf").read_bytes()
    kinds = set()
    for k in range(64):                                    # through the packed data, past the first header
        at = 80 + k * (len(raw) - 200) // 64
        (tmp_path / "model.3mf").write_bytes(raw[:at] + bytes([raw[at] ^ 0x5A]) + raw[at + 1:])
        try:
            read_3mf_text(tmp_path / "model.3mf")
            kinds.add("read")
        except ExportError as exc:
            assert "model.3mf: " in str(exc)
            kinds.add(str(exc).split("(")[1][:12])
    assert len(kinds) > 1, kinds
    assert main(["check", str(tmp_path)]) == 4
    out = capsys.readouterr()
    assert "internal error" not in out.err and "FAIL 3mf" in out.out
