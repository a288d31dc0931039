"""Issue 32: config inputs that used to end in an internal error (exit 1) or a false rejection.

Each bad file ends through the command line (``fabricate run``) with exit 2 and one line naming
the key, the value and what was expected; a partial ``outputs.nesting`` section takes the README's
defaults for the keys it leaves out.
"""
from __future__ import annotations

import pytest

from fabricate.app.cli import main
from fabricate.app.config import MAX_MM, load_config

DOME = "input: {shape: {name: dome, params: {meridians: 6, rings: 3}}}\n"


def run_error(tmp_path, capsys, text: str) -> str:
    """The one error line of ``fabricate run`` on ``text`` (exit 2 asserted)."""
    path = tmp_path / "job.yaml"
    path.write_text(text)
    code = main(["run", str(path), "--out", str(tmp_path / "out"), "-q"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "internal error" not in err and "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert not (tmp_path / "out" / "job").exists()
    return lines[0]


@pytest.mark.parametrize("value, fragment", [
    ("!!timestamp foo", "'foo'"),
    ("!!timestamp 99999-01-01", "'99999-01-01'"),
    ("!!timestamp 2001-13-14", "'2001-13-14'"),
    ("!!bool maybe", "'maybe'"),
])
def test_a_bad_explicit_tag_names_the_line_the_value_and_what_is_expected(tmp_path, capsys, value, fragment):
    line = run_error(tmp_path, capsys, DOME + f"name: {value}\n")
    assert "job.yaml:2:" in line and fragment in line and "expected" in line, line


@pytest.mark.parametrize("text, key", [
    (DOME + 'parts: {"foo[1]": 3}\n', "parts.foo[1]: unknown key"),
    (DOME + '"[x]": 3\n', "[x]: unknown key"),
    (DOME + 'parts: {"literal[1]": 3}\n', "parts.literal[1]: unknown key"),
    (DOME + 'parts: {"str": 3}\n', "parts.str: unknown key"),
    (DOME + 'optimize: {fixed: [1, "x[2]"]}\n', "optimize.fixed"),
])
def test_an_unknown_key_with_brackets_is_named_as_written(tmp_path, capsys, text, key):
    line = run_error(tmp_path, capsys, text)
    assert key in line and "job.yaml:" in line, line


@pytest.mark.parametrize("text, key", [
    ("structure: {check: report, section: {shape: plate, depth: 1e308, width: 20}}\n", "structure.section.depth"),
    ("structure: {sizing: {sections: [{shape: plate, depth: 100, width: 1e308}]}}\n",
     "structure.sizing.sections.0.width"),
    ("structure: {section: {shape: rhs, depth: 200, width: 100, web: 1e300}}\n", "structure.section.web"),
])
def test_a_section_size_beyond_physical_is_refused_naming_the_bound(tmp_path, capsys, text, key):
    line = run_error(tmp_path, capsys, DOME + text)
    assert f"{key}: value 1e+3" in line and f"{MAX_MM:g}] mm" in line, line


@pytest.mark.parametrize("text, key, bound", [
    ("outputs: {nesting: {steel: {sheet_mm: [1e308, 2500]}}}\n", "outputs.nesting.steel.sheet_mm.0", "100000]"),
    ("outputs: {nesting: {glass: {sheet_mm: [-1, 3000]}}}\n", "outputs.nesting.glass.sheet_mm.0", "(0, "),
    ("parts: {limits: {sheet_mm: [6000, 1e308]}}\n", "parts.limits.sheet_mm.1", "100000]"),
    ("structure: {loads: {snow: 1e308}}\n", "structure.loads.snow", "kN/m2"),
    ("structure: {combinations: [{name: a, kind: uls, factors: {snow: 1e308}}]}\n",
     "structure.combinations.0.factors", "[0, 10]"),
    ("structure: {up: [1e308, 1e308, 0]}\n", "structure.up", "finite"),
])
def test_other_sizes_and_loads_beyond_physical_are_refused(tmp_path, capsys, text, key, bound):
    line = run_error(tmp_path, capsys, DOME + text)
    assert key in line and bound in line, line


# -- outputs.nesting: a partial section keeps the other defaults ----------------------------------
@pytest.mark.parametrize("section, expect", [
    ("{glass: {margin_mm: 5}}", {"glass": dict(sheet_mm=(6000.0, 3210.0), margin_mm=5.0, kerf_mm=10.0)}),
    ("{steel: {kerf_mm: 1.5}}", {"steel": dict(sheet_mm=(12000.0, 2500.0), margin_mm=10.0, kerf_mm=1.5),
                                 "glass": dict(sheet_mm=(6000.0, 3210.0), margin_mm=20.0, kerf_mm=10.0)}),
    ("{glass: {rotation: false}, steel: {sheet_mm: [6000, 2000]}}",
     {"glass": dict(sheet_mm=(6000.0, 3210.0), margin_mm=20.0, kerf_mm=10.0, rotation=False),
      "steel": dict(sheet_mm=(6000.0, 2000.0), margin_mm=10.0, kerf_mm=3.0)}),
    ("{glass: null}", {"glass": dict(sheet_mm=(6000.0, 3210.0), margin_mm=20.0, kerf_mm=10.0)}),
])
def test_a_partial_nesting_section_takes_the_documented_defaults(tmp_path, section, expect):
    path = tmp_path / "job.yaml"
    path.write_text(DOME + f"outputs: {{nesting: {section}}}\n")
    cfg = load_config(path)
    for material, values in expect.items():
        sheet = getattr(cfg.outputs.nesting, material)
        for key, value in values.items():
            assert getattr(sheet, key) == value, (material, key)
    again = load_config(path, overrides={"outputs.nesting.steel.margin_mm": 4})
    assert again.outputs.nesting.steel.margin_mm == 4.0 and again.outputs.nesting.steel.kerf_mm == (
        expect.get("steel", {}).get("kerf_mm", 3.0))


def test_the_nesting_dump_the_cut_files_take_is_complete(tmp_path):
    path = tmp_path / "job.yaml"
    path.write_text(DOME + "outputs: {nesting: {glass: {margin_mm: 5}}}\n")
    dump = load_config(path).outputs.nesting.model_dump()
    assert dump["glass"] == {"sheet_mm": (6000.0, 3210.0), "margin_mm": 5.0, "kerf_mm": 10.0, "rotation": True}
    assert dump["steel"] == {"sheet_mm": (12000.0, 2500.0), "margin_mm": 10.0, "kerf_mm": 3.0, "rotation": True}


def test_a_bad_nesting_key_still_names_its_line(tmp_path, capsys):
    line = run_error(tmp_path, capsys, DOME + "outputs:\n  nesting:\n    glass: {margin_mm: -5}\n")
    assert "job.yaml:4: outputs.nesting.glass.margin_mm: value -5" in line, line
