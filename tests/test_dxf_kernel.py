"""The DXF text reader's compiled kernels (:mod:`fabricate.export._dxf_kernel`) read every file as its NumPy
path does: the same outlines, sheets and facts, or the same error."""
import numpy as np
import pytest
from cad_fixtures import dome_parts

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
