"""The DXF text reader's compiled kernels (:mod:`fabricate.export._dxf_kernel`) read every file as its NumPy
path does: the same outlines, sheets and facts, or the same error."""
import numpy as np
import pytest
from cad_fixtures import dome_parts
from test_check_dxf_strict import drop_y, set_value

from fabricate.export import dxf_text, write_cut_files, write_dxf
from optimize import kernels
from optimize.errors import ExportError

pytest.importorskip("numba")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    from fabricate.app.config import NestingSection

    parts = dome_parts(6, 3)
    out = tmp_path_factory.mktemp("dxfkernel")
    write_dxf(parts, out / "outlines.dxf")
    write_cut_files(parts, out, NestingSection().model_dump())
    return out


def _read(path, on: bool, monkeypatch):
    monkeypatch.setattr(kernels, "ENABLED", on)
    monkeypatch.setattr(dxf_text, "KERNEL_FROM_BYTES", 0)
    assert (dxf_text._kernel(1) is not None) == on
    try:
        return dxf_text.read_outlines_text(path, sheets=True)
    except ExportError as exc:
        return str(exc)


def _same(a, b) -> None:
    assert type(a) is type(b), (a, b)
    if isinstance(a, str):
        assert a == b
        return
    (out_a, facts_a), (out_b, facts_b) = a, b
    assert list(out_a) == list(out_b) and all(np.array_equal(out_a[k], out_b[k]) for k in out_a)
    assert facts_a.keys() == facts_b.keys()
    for k in facts_a:
        assert np.array_equal(facts_a[k], facts_b[k]) if k == "sheets" else facts_a[k] == facts_b[k], k


def test_the_kernel_reads_the_outlines_and_cut_files_as_numpy_does(files, monkeypatch):
    paths = [files / "outlines.dxf"] + sorted(files.glob("cut_*.dxf"))
    assert len(paths) >= 3
    for path in paths:
        mine = _read(path, True, monkeypatch)
        assert not isinstance(mine, str) and mine[0] and mine[1]["lint"] == []
        _same(mine, _read(path, False, monkeypatch))


EDITS = {
    "crlf": lambda t: t.replace(b"\n", b"\r\n"),
    "no newline at the end": lambda t: t.rstrip(b"\n"),
    "a line more": lambda t: t + b"  0\n",
    "a signed code": lambda t: t.replace(b"\n 10\n", b"\n+10\n", 1),
    "a negative code": lambda t: t.replace(b"\n 10\n", b"\n-10\n", 3),
    "a space after the code": lambda t: t.replace(b"\n 10\n", b"\n 10 \n", 1),
    "a code of nine characters": lambda t: t.replace(b"\n 10\n", b"\n        10\n", 1),
    "an empty code line": lambda t: t.replace(b"\n 10\n", b"\n\n", 1),
    "a code of spaces": lambda t: t.replace(b"\n 10\n", b"\n   \n", 1),
    "a code with a space inside": lambda t: t.replace(b"\n 10\n", b"\n 1 0\n", 1),
    "a code that is not a number": lambda t: t.replace(b"\n 10\n", b"\n1x\n", 1),
    "a tab before the code": lambda t: t.replace(b"\n 10\n", b"\n\t10\n", 1),
    "an empty file": lambda t: b"",
    "a duplicate handle": lambda t: _handles(t, lambda h: [h[0], h[0]] + h[2:]),
    "a handle that is not hexadecimal": lambda t: _handles(t, lambda h: [h[0], b"G1"] + h[2:]),
    "a handle of no characters": lambda t: _handles(t, lambda h: [h[0], b" "] + h[2:]),
    "a handle with 0x": lambda t: _handles(t, lambda h: [h[0], b"0x" + h[1]] + h[2:]),
    "two handles equal but for their case": lambda t: _handles(t, lambda h: [h[0], b"fffffa", b"FFFFFA"] + h[3:]),
    "two lower case handles the same": lambda t: _handles(t, lambda h: [h[0], b"fffffa", b"fffffa"] + h[3:]),
    "layers with spaces and tabs around": lambda t: t.replace(b"\n  8\nCUT\n", b"\n  8\n \tCUT \n", 7),
    "a layer name that is not UTF-8": lambda t: t.replace(b"\n  8\nCUT\n", b"\n  8\nCUT\xff\n", 1),
    "two names, one bad byte each": lambda t: t.replace(b"\n  8\nCUT\n", b"\n  8\nCU\xfe\n", 1).replace(
        b"\n  8\nCUT\n", b"\n  8\nCU\xff\n", 1),
}


def _handles(text: bytes, change) -> bytes:
    """``text`` with the handles (code 5) of the ENTITIES section replaced by ``change(handles)``."""
    import re

    at = text.index(b"\nENTITIES\n")
    parts = re.split(rb"(\n  5\n)([^\n]*)(?=\n)", text[at:])
    handles = parts[2::3]
    new = change(list(handles))
    assert len(new) == len(handles) > 2
    parts[2::3] = new
    return text[:at] + b"".join(parts)


@pytest.mark.parametrize("edit", EDITS)
def test_edited_files_read_the_same_or_fail_the_same(files, tmp_path, monkeypatch, edit):
    raw = (files / "outlines.dxf").read_bytes()
    new = EDITS[edit](raw)
    assert new != raw
    path = tmp_path / "edited.dxf"
    path.write_bytes(new)
    mine = _read(path, True, monkeypatch)
    _same(mine, _read(path, False, monkeypatch))
    if edit in LINT:
        assert any(LINT[edit] in x for x in mine[1]["lint"]), mine[1]["lint"]


LINT = {"a duplicate handle": "1 duplicate entity handles", "a handle that is not hexadecimal": "not hexadecimal",
        "a handle of no characters": "not hexadecimal",
        "two lower case handles the same": "1 duplicate entity handles"}
"""The edits that a lint message must name (the others read without one, or fail)."""


def test_small_files_do_not_load_the_kernels(monkeypatch):
    monkeypatch.setattr(kernels, "ENABLED", True)
    assert dxf_text._kernel(dxf_text.KERNEL_FROM_BYTES - 1) is None
    assert dxf_text._kernel(dxf_text.KERNEL_FROM_BYTES) is not None


STRICT = {   # edit: the words of the error, or None: the file reads (ezdxf reads it too)
    "a TEXT insertion x that is not a number": (lambda t: set_value(t, b"ETCH", b"TEXT", b" 10", b"abc"),
                                                "'abc' (group code 10): expected a finite number"),
    "an infinite ETCH vertex": (lambda t: set_value(t, b"ETCH", b"LWPOLYLINE", b" 10", b"inf"),
                                "'inf' (group code 10): expected a finite number"),
    "a vertex too large for a double": (lambda t: set_value(t, b"BEVEL", b"LWPOLYLINE", b" 20", b"1e309"),
                                        "'1e309' (group code 20): expected a finite number"),
    "a vertex just past the largest double": (lambda t: set_value(t, b"CUT", b"LWPOLYLINE", b" 20", b"1.8e308"),
                                              "'1.8e308' (group code 20): expected a finite number"),
    "a vertex just below the largest double": (lambda t: set_value(t, b"BEVEL", b"LWPOLYLINE", b" 20",
                                                                b"1.7976931348623157e308"), None),
    "a TEXT height with a comma": (lambda t: set_value(t, b"ETCH", b"TEXT", b" 40", b"2,5"),
                                   "'2,5' (group code 40): expected a finite number"),
    "a colour that is nan": (lambda t: set_value(t, b"CUT", b"LWPOLYLINE", b" 70", b"nan"),
                             "'nan' (group code 70): expected a finite number"),
    "an outline vertex without its y": (drop_y, "not by its y (group code 20)"),
    "binary data that is not hexadecimal": (lambda t: t.replace(b"\n  8\nCUT\n", b"\n  8\nCUT\n310\nZZ\n", 1),
                                            "'ZZ' (group code 310): expected hexadecimal binary data"),
    "numbers written otherwise": (lambda t: set_value(set_value(t, b"ETCH", b"TEXT", b" 10", b" +.5E+2 "),
                                                   b"ETCH", b"TEXT", b" 20", b"7."), None),
    "a count written as a float": (lambda t: set_value(t, b"CUT", b"LWPOLYLINE", b" 90", b"4.0"), None),
    "a comment between x and y": (lambda t: t.replace(b"\n 20\n", b"\n999\nhello\n 20\n", 1), None),
}


@pytest.mark.parametrize("edit", STRICT)
def test_values_are_read_as_strictly_as_ezdxf_reads_them(files, tmp_path, monkeypatch, edit):
    """Every value of a numeric group code in any entity a finite number, every x followed by its y, binary
    data hexadecimal: else the file fails with its line and value, on both paths; ezdxf refuses the same
    files (and reads the others), but for numbers too large for a double, which it reads as infinite."""
    import ezdxf

    change, words = STRICT[edit]
    raw = (files / "outlines.dxf").read_bytes()
    new = change(raw)
    assert new != raw
    path = tmp_path / "edited.dxf"
    path.write_bytes(new)
    mine = _read(path, True, monkeypatch)
    _same(mine, _read(path, False, monkeypatch))
    if words is None:
        assert not isinstance(mine, str), mine
        ezdxf.readfile(path)
        return
    assert isinstance(mine, str) and words in mine and f"{path}: line " in mine, mine
    line = int(mine.split(": line ")[1].split(":")[0])
    shown = mine.split(": line ")[1].split(": ", 1)[1]
    if shown.startswith("'"):                                  # the line holds the value quoted
        assert new.split(b"\n")[line - 1].decode() == shown[1:].split("' (group code")[0]
    if edit not in ("an infinite ETCH vertex", "a vertex too large for a double", "a vertex just past the "
                    "largest double"):
        with pytest.raises(ezdxf.DXFStructureError):
            ezdxf.readfile(path)


def test_the_numeric_codes_are_ezdxfs():
    from ezdxf.lldxf.types import BINARY_DATA, POINT_CODES, TYPE_TABLE

    numeric = {c for c, t in TYPE_TABLE.items() if t in (int, float)}
    assert set(np.flatnonzero(dxf_text.IS_NUMBER).tolist()) == numeric
    assert set(np.flatnonzero(dxf_text.IS_POINT).tolist()) == set(POINT_CODES)
    assert set(np.flatnonzero(dxf_text.IS_BINARY).tolist()) == set(BINARY_DATA)


TOKENS = [b"0", b"1", b"-2.5", b"+.5", b"1.", b".", b"", b" ", b"1e5", b"1e", b"e5", b"1e+", b"1.5e-3", b"--1",
          b"1_0", b"inf", b"-inf", b"nan", b"0x10", b"1 2", b" 3 ", b"\t4\v", b"\f5", b"1e308",
          b"1.7976931348623157e308", b"1.7976931348623159e308", b"9.9e307", b"10e307", b"0.1e309", b"0.01e310",
          b"1e309", b"00001e308",
          b"0.000e999", b"1e-999", b"1e99999999999999999999", b"1e-99999999999999999999", b"1.2.3", b"+-1", b"1d5",
          b"\xff", b"12345678901234567890123456789e290"]


def test_the_kernel_and_numpy_find_the_same_first_value_that_is_not_a_finite_number():
    """Each token alone, and after all the good ones, read by both: the first bad value is the same, and a
    token is good exactly when Python's float reads it finite and it has no letters but e (no nan, inf, _)."""
    kernel = kernels.load("fabricate.export._dxf_kernel")

    def first(values, use_kernel):
        data = b"\n".join(values) + b"\n" + b" " * 16
        ends = np.flatnonzero(np.frombuffer(data, np.uint8) == 10)
        vs = np.concatenate([[0], ends[:-1] + 1])
        return dxf_text._first_not_number(np.frombuffer(data, np.uint8), data, vs, ends,
                                          np.arange(len(values)), kernel if use_kernel else None)

    def finite(tok):
        try:
            return np.isfinite(float(tok)) and not any(c in tok.lower() for c in b"_infa")
        except ValueError:
            return False

    good = [t for t in TOKENS if finite(t)]
    assert len(good) > 10 and len(good) < len(TOKENS) - 10
    for tok in TOKENS:
        want = None if finite(tok) else 0
        assert first([tok], True) == first([tok], False) == want, tok
        want = None if finite(tok) else len(good)
        assert first(good + [tok, b"x"], True) == first(good + [tok, b"x"], False) == (want if want is not None
                                                                                       else len(good) + 1), tok
