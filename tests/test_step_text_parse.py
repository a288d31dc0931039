"""The vectorised STEP record parser of the text reader: same reading of other layouts, one-line errors."""
import re
import tracemalloc

import numpy as np
import pytest
from cad_fixtures import dome_parts

from fabricate.export import write_step
from fabricate.export.step_text import read_step_text
from fabricate.export.step_tokens import _digits, _eight_digits
from optimize.errors import ExportError


@pytest.fixture(scope="module")
def step(tmp_path_factory):
    path = tmp_path_factory.mktemp("steptok") / "model.step"
    write_step(dome_parts(6, 3), path)
    return path, path.read_text()


def _read(tmp_path, text, name="x.step"):
    p = tmp_path / name
    p.write_text(text)
    return read_step_text(p)


def _same(a, b):
    assert list(a) == list(b)
    for k in a:
        for key, v in a[k].items():
            if key == "faces":
                assert all(np.array_equal(x, y) for x, y in zip(v, b[k][key]))
            else:
                assert v == b[k][key], (k, key)


def test_reference_values_eight_digits_at_once():
    words = [b"7,", b"12)", b"1234567,", b"12345678", b"90=", b"7\xff\xff", b"x1"]
    x = np.array([int.from_bytes(w.ljust(8, b" ")[:8], "little") for w in words], dtype=np.uint64)
    n = _digits(x)
    assert n.tolist() == [1, 2, 7, 8, 2, 1, 0]
    assert _eight_digits(x, n)[:6].tolist() == [7, 12, 1234567, 12345678, 90, 7]


def test_other_layouts_read_the_same(step, tmp_path):
    path, text = step
    mine = read_step_text(path)
    # whitespace between tokens, CR LF, records over lines and a comment: the same solids
    spaced = text.replace(",", " ,\r\n  ").replace("=", " = ").replace(";\n", ";\r\n/* c */ ")
    _same(_read(tmp_path, spaced)[0], mine[0])
    # big ids (more than eight digits) and a string with ';', '#' and an escaped quote
    big = re.sub(r"#(\d+)", lambda m: f"#{int(m.group(1)) + 3_000_000_000}", text)
    big = big.replace("APPLICATION_CONTEXT('", "APPLICATION_CONTEXT('it''s #1; ", 1)
    _same(_read(tmp_path, big, "big.step")[0], mine[0])


@pytest.mark.parametrize("edit, words", [
    (lambda t: re.sub(r"(CARTESIAN_POINT\('',\()([^,]+)", r"\g<1>1.2.3", t, count=1), "not a finite number"),
    (lambda t: re.sub(r"(CARTESIAN_POINT\('',\()([^,]+),", r"\g<1>", t, count=1), "3 numbers"),
    (lambda t: re.sub(r"(DIRECTION\('',\()([^,]+)", r"\g<1>abc", t, count=1), "not part of a number"),
    (lambda t: re.sub(r"(EDGE_CURVE\('',#\d+,)#\d+", r"\g<1>#99999999", t, count=1), "is not a VERTEX_POINT"),
    (lambda t: re.sub(r"(EDGE_CURVE\('',#\d+),#\d+", r"\g<1>", t, count=1), "expected 3"),
    (lambda t: re.sub(r"(VERTEX_POINT\('',)#", r"\g<1>", t, count=1), "expected 1"),
    (lambda t: re.sub(r"(ORIENTED_EDGE\('',\*,\*,#\d+,\.)T", r"\g<1>X", t, count=1), "not ('<string>'"),
    (lambda t: re.sub(r"(EDGE_LOOP\('',\(#\d+),", r"\g<1>,,", t, count=1), "(#a,#b,...)"),
    (lambda t: t.replace("=VERTEX_POINT('',#", "=VERTEX_POINT('',#1234567890123", 1), "more than 11 digits"),
    (lambda t: t.replace("=LINE('',", "=LINE('", 1), "closing quote"),
])
def test_a_malformed_record_is_one_line_naming_the_entity(step, tmp_path, edit, words):
    _, text = step
    new = edit(text)
    assert new != text
    with pytest.raises(ExportError) as e:
        _read(tmp_path, new)
    msg = str(e.value)
    assert words in msg and "\n" not in msg and "x.step" in msg


def test_a_hostile_huge_line_is_refused_in_bounded_time_and_memory(step, tmp_path):
    _, text = step
    huge = text.replace("CARTESIAN_POINT('',(", "CARTESIAN_POINT('',(" + "1" * 20_000_000, 1)
    p = tmp_path / "huge.step"
    p.write_text(huge)
    tracemalloc.start()
    with pytest.raises(ExportError, match="at most 96 characters"):
        read_step_text(p)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 40 * p.stat().st_size        # a few copies of the file, never its square
