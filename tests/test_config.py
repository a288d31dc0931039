"""Run configs: defaults, paths, overrides and every error message (file, line, key, value, allowed)."""
from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from fabricate.app.config import RunConfig, TolerancesSection, load_config, parse_config
from optimize.modelling import shapes
from optimize.errors import ConfigError
from optimize.mesh.io import write_mesh
from optimize.tolerances import Tolerances

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture
def folder(tmp_path) -> Path:
    """A folder with a small mesh file ``data/grid.obj`` and a config sub-folder ``cfg/``."""
    (tmp_path / "data").mkdir()
    (tmp_path / "cfg").mkdir()
    write_mesh(tmp_path / "data" / "grid.obj", shapes.grid(3, 3))
    return tmp_path


def write(folder: Path, text: str, name: str = "job.yaml") -> Path:
    path = folder / "cfg" / name
    path.write_text(text)
    return path


def error_of(path: Path, **kw) -> str:
    with pytest.raises(ConfigError) as info:
        load_config(path, **kw)
    assert info.value.exit_code == 2
    return str(info.value)


def test_minimal_config_fills_defaults_and_resolves_paths(folder):
    cfg = load_config(write(folder, "input:\n  mesh: ../data/grid.obj\n"))
    assert cfg.name == "job"  # the file name when the config has none
    assert cfg.input.kind == "mesh"
    assert cfg.input.mesh == (folder / "data" / "grid.obj").resolve()
    assert cfg.tolerances.to_tolerances() == Tolerances()
    assert cfg.layer_distances() == [0.0, -cfg.parts.beam_depth]
    assert cfg.mm_per_unit == 1.0
    assert cfg.source == folder / "cfg" / "job.yaml"


def test_tolerance_section_mirrors_the_tolerances_object():
    assert set(TolerancesSection.model_fields) - {"requirements"} == set(Tolerances().as_dict())


def test_units_scale_and_overrides(folder):
    path = write(folder, "name: a\ninput: {mesh: ../data/grid.obj}\nunits: m\nscale: 2\n")
    cfg = load_config(path, overrides={"parts.glass_thickness": 8, "offset.distances": [0, 150]})
    assert cfg.mm_per_unit == 2000.0
    assert cfg.parts.glass_thickness == 8.0
    assert cfg.layer_distances() == [0.0, 150.0]


def test_as_run_dict_round_trips(folder):
    cfg = load_config(write(folder, "input: {mesh: ../data/grid.obj}\noutputs: {3mf: false}\n"))
    data = yaml.safe_load(yaml.safe_dump(cfg.as_dict()))
    assert data["outputs"]["3mf"] is False
    again = parse_config(data, source=folder / "elsewhere" / "x.yaml")  # absolute paths survive a move
    assert again.as_dict() == cfg.as_dict()


def _holds(got, written, where, key=()):
    """``got`` (a config as run, ``as_dict``) holds every value of ``written`` (its YAML data)."""
    if isinstance(written, dict):
        assert isinstance(got, dict), (where, key)
        for k, v in written.items():
            assert k in got, (where, key + (k,))
            _holds(got[k], v, where, key + (k,))
    elif isinstance(written, list):
        assert isinstance(got, list) and len(got) == len(written), (where, key)
        for i, (g, w) in enumerate(zip(got, written)):
            _holds(g, w, where, key + (i,))
    elif key[:1] == ("input",) and key[-1] in ("mesh", "control", "surface"):  # paths are resolved against the file's folder
        assert Path(got) == (where.parent / written).resolve(), (where, key)
    elif isinstance(written, bool) and isinstance(got, str):  # YAML's off/on, kept as the key's word
        assert got in (("on", "yes", "true") if written else ("off", "no", "false")), (where, key, got)
    else:
        assert got == written and type(got) in (type(written), float), (where, key, got, written)


def test_every_example_config_is_valid():
    paths = sorted((REPO / "configs").glob("*.yaml"))
    names = {p.stem for p in paths}
    assert {"quickstart", "reference", "railway_station", "trefoil_band", "developable_strips", "dome",
            "freeform_canopy"} <= names, names
    for path in paths:
        cfg = load_config(path)
        raw = yaml.safe_load(path.read_text()) or {}
        # every value the file writes is the value the run takes (nothing dropped, coerced or renamed)
        _holds(cfg.as_dict(), raw, path)
        assert cfg.name == raw.get("name", path.stem)
        for key in ("mesh", "control", "surface"):  # every file a config reads is in the repository
            file = getattr(cfg.input, key, None)
            if file is not None:
                assert Path(file).resolve().is_relative_to(REPO), (path.name, file)
                assert Path(file).is_file(), (path.name, file)


def test_reference_config_lists_every_key():
    text = (REPO / "configs" / "reference.yaml").read_text()
    data = yaml.safe_load(text)
    for section in ("subdivision", "optimize", "tolerances", "offset", "parts", "outputs"):
        model = RunConfig.model_fields[section].annotation
        assert set(data[section]) == set(model.allowed_keys()), section
    for key in ("shape", "mesh", "control", "surface", "edge_length"):
        assert f"{key}:" in text  # the alternatives are shown, commented out
    assert {"name", "input", "units", "scale"} <= set(data)


# Each case: YAML text, then fragments the message must contain (file:line, key path, value, allowed).
CASES = {
    "misspelt key": ("input: {mesh: ../data/grid.obj}\noptimize:\n  targte: conical\n",
                     ["job.yaml:3", "optimize.targte", "unknown key", "did you mean 'target'", "allowed: target"]),
    "misspelt section": ("input: {mesh: ../data/grid.obj}\nsubdivison: {levels: 1}\n",
                         ["job.yaml:2", "subdivison", "did you mean 'subdivision'"]),
    "bad choice": ("input: {mesh: ../data/grid.obj}\noptimize: {method: sqpp}\n",
                   ["job.yaml:2", "optimize.method", "'sqpp'", "did you mean 'sqp'", "'penalty'"]),
    "bad number": ("input: {mesh: ../data/grid.obj}\nparts:\n  glass_thickness: thick\n",
                   ["job.yaml:3", "parts.glass_thickness", "'thick'", "expected a number in (0, 200]"]),
    "out of range": ("input: {mesh: ../data/grid.obj}\noptimize: {max_iter: 0}\n",
                     ["optimize.max_iter", "value 0", "an integer in 1..10000"]),
    "negative gap": ("input: {mesh: ../data/grid.obj}\nparts: {joint_gap: -1}\n",
                     ["parts.joint_gap", "value -1", "a number in [0, 1000]"]),
    "zero tolerance": ("input: {mesh: ../data/grid.obj}\ntolerances: {planarity: 0}\n",
                       ["tolerances.planarity", "value 0", "a number in [1e-12, 1]"]),
    "missing input": ("name: x\n", ["job.yaml", "input", "required key is missing"]),
    "two inputs": ("input: {mesh: ../data/grid.obj, control: ../data/grid.obj}\n",
                   ["job.yaml:1", "input", "exactly one of shape, mesh, control, surface", "mesh, control"]),
    "missing file": ("input: {mesh: nothere.obj}\n",
                     ["input.mesh", "'nothere.obj'", "file not found", "nothere.obj"]),
    "surface without edge length": ("input: {surface: ../data/grid.obj}\n", ["input", "needs edge_length"]),
    "edge length without surface": ("input: {mesh: ../data/grid.obj, edge_length: 2}\n",
                                    ["input", "edge_length applies only to a surface"]),
    "bad irregular": ("input: {surface: ../data/grid.obj, edge_length: 2, irregular: corners}\n",
                      ["job.yaml:1", "input.irregular", "'corners'", "'faces'", "'vertices'"]),
    "bad side word": ("input: {surface: ../data/grid.obj, edge_length: 2, side: inward}\n",
                      ["job.yaml:1", "input.side", "'inward'", "'keep'"]),
    "zero side": ("input: {surface: ../data/grid.obj, edge_length: 2, side: [0, 0, 0]}\n",
                  ["input", "side [0.0, 0.0, 0.0]", "nonzero"]),
    "negative radius": ("input: {surface: ../data/grid.obj, edge_length: 2, radius: -1}\n",
                        ["input.radius", "value -1", "a number in (0, 1e7]"]),
    "side without surface": ("input: {mesh: ../data/grid.obj, side: keep}\n",
                             ["input", "side applies only to a surface"]),
    "irregular without surface": ("input: {mesh: ../data/grid.obj, irregular: faces}\n",
                                  ["input", "irregular applies only to a surface"]),
    "bad fixed word": ("input: {mesh: ../data/grid.obj}\noptimize: {fixed: bundary}\n",
                       ["optimize.fixed", "'bundary'", "did you mean 'boundary'", "'corners'"]),
    "bad fixed index": ("input: {mesh: ../data/grid.obj}\noptimize: {fixed: [1, x]}\n",
                        ["optimize.fixed.1", "'x'", "valid integer"]),
    "negative fixed index": ("input: {mesh: ../data/grid.obj}\noptimize: {fixed: [1, -2]}\n",
                             ["optimize.fixed", ">= 0"]),
    "one layer": ("input: {mesh: ../data/grid.obj}\noffset: {distances: [0]}\n",
                  ["offset.distances", "at least 2 items"]),
    "equal layers": ("input: {mesh: ../data/grid.obj}\noffset: {distances: [0, 0]}\n",
                     ["offset.distances", "distinct"]),
    "depth disagrees": ("input: {mesh: ../data/grid.obj}\noffset: {distances: [0, 100]}\nparts: {beam_depth: 200}\n",
                        ["job.yaml:3", "parts.beam_depth", "200", "offset.distances", "[0.0, 100.0]"]),
    "bad unit": ("input: {mesh: ../data/grid.obj}\nunits: km\n",
                 ["job.yaml:2", "units", "'km'", "'mm'", "'ft'"]),
    "bad name": ("name: a b/c\ninput: {mesh: ../data/grid.obj}\n",
                 ["job.yaml:1", "name", "'a b/c'", "names a folder"]),
    "bad output key": ("input: {mesh: ../data/grid.obj}\noutputs: {stpe: false}\n",
                       ["outputs.stpe", "did you mean 'step'", "3mf"]),
    "bad output value": ("input: {mesh: ../data/grid.obj}\noutputs: {step: maybe}\n",
                         ["outputs.step", "'maybe'", "valid boolean"]),
    "unknown design": ("input:\n  shape: {name: railway_statoin}\n",
                       ["job.yaml:2", "input.shape", "unknown design 'railway_statoin'",
                        "did you mean 'railway_station'"]),
    "unknown design parameter": ("input:\n  shape: {name: dome, params: {no_such_parameter: 3}}\n",
                                 ["input.shape", "unknown parameter 'no_such_parameter'", "allowed:"]),
    "section not a mapping": ("input: {mesh: ../data/grid.obj}\nparts: 12\n",
                              ["job.yaml:2", "parts", "value 12", "valid dictionary"]),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_error_message_names_file_line_key_value_and_allowed(folder, case):
    text, fragments = CASES[case]
    message = error_of(write(folder, text))
    for fragment in fragments:
        assert fragment in message, f"{case}: {fragment!r} not in {message!r}"


def test_several_problems_are_all_listed(folder):
    message = error_of(write(folder, "input: {mesh: ../data/grid.obj}\noptimize: {method: x, max_iter: 0}\n"
                                     "units: km\n"))
    assert "3 problems" in message
    assert message.count("\n") == 3
    assert message.index("optimize.method") < message.index("units")  # ordered by line


def test_yaml_syntax_error_names_line(folder):
    message = error_of(write(folder, "input: {mesh: grid.obj\n  foo: [\n"))
    assert "job.yaml:2" in message and "not valid YAML" in message


def test_non_mapping_file_and_missing_file(folder):
    assert "expected a mapping of sections" in error_of(write(folder, "- a\n- b\n"))
    assert "cannot read the config file" in error_of(folder / "cfg" / "absent.yaml")


def test_unsafe_yaml_is_refused(folder):
    message = error_of(write(folder, "input: !!python/object/apply:os.system ['echo hi']\n"))
    assert "not valid YAML" in message


def test_override_errors_name_the_set_option(folder):
    path = write(folder, "input: {mesh: ../data/grid.obj}\n")
    message = error_of(path, overrides={"parts.glas_thickness": 8})
    assert "parts.glas_thickness" in message and "did you mean 'glass_thickness'" in message
    assert "from --set parts.glas_thickness=8" in message
    message = error_of(path, overrides={"input.mesh.x": 1})
    assert "input.mesh is" in message and "not a section" in message


def test_reference_config_states_every_range():
    """Every key with a range has it on its line of configs/reference.yaml, as the messages write it."""
    from fabricate.app.config_errors import field_range
    lines = (REPO / "configs" / "reference.yaml").read_text().splitlines()
    checked = 0
    for section, field in RunConfig.model_fields.items():
        model = next((a for a in getattr(field.annotation, "__args__", (field.annotation,))
                      if hasattr(a, "model_fields")), None)
        keys = [(section, k.alias or n) for n, k in model.model_fields.items()] if model else [(section,)]
        for loc in keys:
            allowed = field_range(RunConfig, loc) or field_range(RunConfig, loc + (0,))
            if allowed is None:
                continue
            text = allowed.split(" in ", 1)[1]
            start = next(i for i, ln in enumerate(lines) if ln.startswith(f"{loc[0]}:"))
            at = start if len(loc) == 1 else next(
                i for i in range(start + 1, len(lines)) if lines[i].lstrip("# ").startswith(f"{loc[1]}:"))
            block = " ".join(lines[at:at + 2])
            assert text in block, (loc, text, block)
            checked += 1
    assert checked >= 20
