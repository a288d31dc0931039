"""The config loader is strict and bounded (issues #15, #14): every hostile or mistaken file
ends in one ConfigError line (exit 2) naming file, line, key, value and what is allowed."""
from __future__ import annotations

import resource
import signal
import tracemalloc
from contextlib import contextmanager
from pathlib import Path

import pytest

from fabricate.app.batch import parse_sets
from fabricate.app.config import MAX_FACES, load_config, override_values, parse_config, takes_list
from fabricate.app.config_yaml import MAX_BYTES, MAX_DEPTH, MAX_NODES, load_yaml
from optimize.errors import ConfigError

DOME = "input: {shape: {name: dome, params: {meridians: 6, rings: 3}}}\n"


@contextmanager
def capped(seconds: float = 20.0, megabytes: float | None = None):
    """Fail (not hang) past ``seconds``; with ``megabytes``, fail when Python's allocations peak above
    it (tracemalloc: slow, so only where the allocation is the point; the alias bomb runs under a hard
    address-space cap in a child process instead)."""
    def expire(signum, frame):
        raise TimeoutError(f"still running after {seconds} s")

    old = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    if megabytes:
        tracemalloc.start()
    try:
        yield
        if megabytes:
            peak = tracemalloc.get_traced_memory()[1] / 2 ** 20
            assert peak < megabytes, f"peak {peak:.0f} MB"
    finally:
        if megabytes:
            tracemalloc.stop()
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def error_of(tmp_path: Path, text: str | bytes, name: str = "job.yaml", **kw) -> str:
    path = tmp_path / name
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(ConfigError) as info:
        load_config(path, **kw)
    assert info.value.exit_code == 2
    message = str(info.value)
    assert "Traceback" not in message and all(str(path) in line or line.startswith("  ")
                                               for line in message.splitlines()), message
    return message


# -- bounded ---------------------------------------------------------------------------
def billion_laughs(levels: int = 9) -> str:
    rows = ['a0: &a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    rows += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, levels)]
    return "\n".join(rows) + "\n" + DOME


def test_alias_bomb_is_refused_in_bounded_time_and_memory(tmp_path):
    text = billion_laughs()
    assert len(text) < 1024  # 9^9 = 387 million strings once expanded
    with capped():
        message = error_of(tmp_path, text)
    assert f"more than {MAX_NODES:,} values" in message and "aliases" in message and "job.yaml:" in message


def test_ordinary_aliases_still_work(tmp_path):
    path = tmp_path / "a.yaml"
    path.write_text("input: {shape: {name: dome, params: &p {meridians: 6, rings: 3}}}\n"
                    "parts: {<<: {glass_thickness: 8}, beam_width: 70}\n")
    cfg = load_config(path)
    assert cfg.input.shape.params == {"meridians": 6, "rings": 3}
    assert cfg.parts.glass_thickness == 8.0 and cfg.parts.beam_width == 70.0


def test_recursive_alias_is_refused(tmp_path):
    assert "nested deeper" in error_of(tmp_path, "input: &a [*a]\n")


DEEP = {"flow list": "input: " + "[" * 5000 + "x" + "]" * 5000,
        "flow map": "input: " + "{a: " * 5000 + "x" + "}" * 5000,
        "block list": "input:\n  " + "- " * 5000 + "x"}


@pytest.mark.parametrize("kind", sorted(DEEP))
def test_deep_nesting_is_refused_without_recursion_error(tmp_path, kind):
    text = DEEP[kind] + "\n"
    with capped():
        message = error_of(tmp_path, text)
    assert f"nested deeper than {MAX_DEPTH} levels" in message and "job.yaml:" in message


def test_latin1_file_names_the_line(tmp_path):
    message = error_of(tmp_path, DOME.encode() + "name: café\n".encode("latin-1"))
    assert "job.yaml:2: not UTF-8 text (byte 0xE9" in message and "save it as UTF-8" in message


def test_utf8_bom_is_read(tmp_path):
    path = tmp_path / "bom.yaml"
    path.write_bytes(b"\xef\xbb\xbf" + DOME.encode())
    assert load_config(path).input.shape.name == "dome"


def test_huge_file_is_refused_naming_the_limit(tmp_path):
    with capped():
        message = error_of(tmp_path, DOME + "#" * MAX_BYTES)
    assert f"larger than {MAX_BYTES // 1024} KiB" in message


def test_control_characters_and_unsafe_tags(tmp_path):
    assert "job.yaml:2: not valid YAML: character U+0001" in error_of(tmp_path, DOME + "name: a\x01\n")
    assert "not valid YAML" in error_of(tmp_path, "input: !!python/name:os.system\n")


def test_huge_design_counts_are_refused_before_building(tmp_path):
    with capped(megabytes=32):
        message = error_of(tmp_path, "input:\n  shape:\n    name: torus_patch\n"
                                     "    params: {nu: 100000, nv: 100000}\n")
    assert "job.yaml:4: input.shape: design torus_patch: parameter nu=100000, expected an integer in 1..300" \
        in message


def test_subdivided_design_size_is_bounded(tmp_path):
    message = error_of(tmp_path, "input: {shape: {name: railway_station, params: {nu: 100, nv: 50}}}\n"
                                 "subdivision: {levels: 3}\n")
    assert "job.yaml:2: input.shape" in message and f"more than {MAX_FACES:,}" in message
    assert "320,000" in message  # 100 x 50 quads x 4^3


@pytest.mark.parametrize("text, fragments", [
    ("parts: {node_sides: 100000000}", ["job.yaml:2: parts.node_sides", "value 100000000", "integer in 6..256"]),
    ("parts: {node_sides: 1e8}", ["parts.node_sides", "value 100000000.0", "integer in 6..256"]),
    ("input: {shape: {name: dome, params: {radius: 1.0e308}}}",
     ["input.shape", "radius=1e+308", "expected a number in (0, 1e6]"]),
    ("input: {shape: {name: developable_strips, params: {turn_deg: x}}}",
     ["input.shape", "turn_deg='x'", "expected a finite number"]),
    ("input: {shape: {name: dome, params: {rings: true}}}", ["rings=True", "expected an integer"]),
    ("input: {shape: {name: trefoil_band, params: {twist: 1}}}", ["twist=1", "true or false"]),
    ("scale: 1e300", ["job.yaml:2: scale", "value 1e+300", "[1e-6, 1e6]"]),
    ("parts: {beam_depth: 1e9}", ["parts.beam_depth", "(0, 10000]"]),
    ("parts: {glass_thickness: 0}", ["parts.glass_thickness", "(0, 200]"]),
    ("parts: {node_radius: -1}", ["parts.node_radius", "[0, 5000]"]),
    ("parts: {density_steel: 1e12}", ["parts.density_steel", "(0, 25000]"]),
    ("optimize: {max_iter: 1000000}", ["optimize.max_iter", "integer in 1..10000"]),
    ("optimize: {fairness: -1}", ["optimize.fairness", "[0, 1e6]"]),
    ("offset: {distances: [0, -200000]}", ["offset.distances.1", "value -200000", "[-10000, 10000]"]),
    ("tolerances: {cad_linear_mm: 100}", ["tolerances.cad_linear_mm", "[1e-7, 1]"]),
    ("subdivision: {levels: 9}", ["subdivision.levels", "integer in 0..6"]),
])
def test_physical_values_have_ranges_named_in_the_message(tmp_path, text, fragments):
    base = DOME if "input" not in text else ""
    message = error_of(tmp_path, base + text + "\n")
    for fragment in fragments:
        assert fragment in message, (fragment, message)
    assert message.count("\n") == 0


# -- strict ----------------------------------------------------------------------------
def test_duplicate_keys_are_refused_naming_both_lines(tmp_path):
    text = DOME + "parts:\n  glass_thickness: 8\noutputs: {step: false}\nparts:\n  beam_width: 80\n"
    message = error_of(tmp_path, text)
    assert "job.yaml:5: parts: duplicate key (also at line 2)" in message
    message = error_of(tmp_path, DOME + "parts: {beam_width: 80, beam_width: 90}\n")
    assert "job.yaml:2: parts.beam_width: duplicate key (also at line 2)" in message


@pytest.mark.parametrize("text, fragments", [
    ("optimize: {max_iter: true}", ["optimize.max_iter", "value True", "boolean"]),
    ("optimize: {max_iter: 20.5}", ["optimize.max_iter", "value 20.5", "integer"]),
    ("parts: {beam_width: yes}", ["parts.beam_width", "value True", "boolean, not a number"]),
    ("parts: {beam_width: .inf}", ["parts.beam_width", "value inf", "(0, 2000]"]),
    ("tolerances: {planarity: .nan}", ["tolerances.planarity", "value nan"]),
    ("offset: {distances: [0, .nan]}", ["offset.distances.1", "value nan"]),
    ("offset: {distances: [0, true]}", ["offset.distances.1", "value True"]),
    ("outputs: {step: 1}", ["outputs.step", "value 1", "valid boolean"]),
    ("name: [a]", ["name", "valid string"]),
])
def test_strict_types_and_finite_numbers(tmp_path, text, fragments):
    message = error_of(tmp_path, DOME + text + "\n")
    for fragment in fragments:
        assert fragment in message, (fragment, message)


def test_yaml_12_numbers_and_words(tmp_path):
    path = tmp_path / "ok.yaml"
    path.write_text(DOME + "name: 2024-01-01\ntolerances: {planarity: 1e-7, conical: 2E-7}\n"
                           "outputs: {check: off, step: no, stl: on}\noffset: {distances: [0, -2e2]}\n")
    cfg = load_config(path)
    assert cfg.name == "2024-01-01"  # a date stays a name
    assert cfg.tolerances.planarity == 1e-7 and cfg.tolerances.conical == 2e-7
    assert cfg.outputs.check == "off" and cfg.outputs.step is False and cfg.outputs.stl is True
    assert cfg.layer_distances() == [0.0, -200.0]
    assert load_yaml("a: 010\nb: 1:30\n", "x") == ({"a": "010", "b": "1:30"}, {("a",): 1, ("b",): 2})


def test_off_is_accepted_for_every_word_key_with_off():
    from fabricate.app.config import OutputsSection
    assert OutputsSection.model_validate({"check": False}).check == "off"
    with pytest.raises(Exception):
        OutputsSection.model_validate({"check": True})  # 'on' is not one of its words


# -- --set -----------------------------------------------------------------------------
def test_comma_list_is_the_list_for_a_list_key(tmp_path):
    assert takes_list("offset.distances") and takes_list("optimize.fixed") and takes_list("input.side")
    assert not takes_list("parts.glass_thickness") and not takes_list("nope.x")
    assert parse_sets(["offset.distances=0,-200"]) == {"offset.distances": [[0, -200]]}
    assert parse_sets(["offset.distances=[0,-200],[0,-300]"]) == {"offset.distances": [[0, -200], [0, -300]]}
    assert parse_sets(["parts.glass_thickness=8,10"]) == {"parts.glass_thickness": [8, 10]}
    assert override_values("optimize.fixed", ["1", "2"]) == [[1, 2]]
    path = tmp_path / "a.yaml"
    path.write_text(DOME)
    cfg = load_config(path, overrides={k: v[0] for k, v in parse_sets(["offset.distances=0,-150"]).items()})
    assert cfg.layer_distances() == [0.0, -150.0]


def test_run_takes_the_comma_list_and_refuses_a_sweep(tmp_path, capsys):
    from fabricate.app.cli import main
    path = tmp_path / "a.yaml"
    path.write_text(DOME)
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q", "--set", "parts.glass_thickness=8,10"]) == 2
    assert "use fabricate batch for sweeps" in capsys.readouterr().err
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q", "--set", "offset.distances=0,-200,-400",
                 "--set", "parts.beam_depth=5"]) == 2
    err = capsys.readouterr().err
    assert "parts.beam_depth: 5.0 disagrees with offset.distances [0.0, -200.0, -400.0]" in err


def test_set_values_are_strict_too(tmp_path):
    path = tmp_path / "a.yaml"
    path.write_text(DOME)
    message = error_of(tmp_path, DOME, overrides={"scale": 1e300})
    assert "scale: value 1e+300" in message and "from --set scale=1e+300" in message
    with pytest.raises(ConfigError, match="expected a key path"):
        parse_config({"input": {}}, overrides={"a..b": 1})


def test_design_params_name_their_own_line(tmp_path):
    message = error_of(tmp_path, "input:\n  shape:\n    name: dome\n    params:\n      meridians: 6\n"
                                 "      rings: 1\n")
    assert "job.yaml:6: input.shape: design dome: parameter rings=1, expected an integer in 2..300" in message


# -- advice names the right key ----------------------------------------------------------
def test_too_deep_beams_are_told_to_reduce_beam_depth(tmp_path, capsys):
    from fabricate.app.cli import main
    path = tmp_path / "deep.yaml"
    path.write_text("input: {shape: {name: dome, params: {radius: 6000, rise: 2500, meridians: 12, rings: 4}}}\n"
                    "optimize: {target: none}\nparts: {beam_depth: 6000}\n"
                    "outputs: {step: false, stl: false, 3mf: false, pictures: false, html: false}\n")
    # no part can be built from the mesh: the mesh, layers and report are written, marked, exit 3 (#30)
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "-q"]) == 3
    err = capsys.readouterr().err
    assert "reduce parts.beam_depth" in err and "reduce parts.beam_width" not in err, err
    assert (tmp_path / "out" / "deep" / "mesh.obj").is_file()


def test_memory_is_capped_in_a_child_for_the_alias_bomb(tmp_path):
    """The alias bomb under a hard address-space cap (not only tracemalloc's view)."""
    import multiprocessing as mp
    path = tmp_path / "bomb.yaml"
    path.write_text(billion_laughs())
    ctx = mp.get_context("fork")
    q = ctx.Queue()
    p = ctx.Process(target=_load_capped, args=(str(path), q))
    p.start()
    p.join(60)
    assert p.exitcode == 0 and q.get(timeout=5) == "ConfigError"


def _load_capped(path: str, q) -> None:
    with open("/proc/self/statm") as fh:
        pages = int(fh.read().split()[0])
    size = pages * resource.getpagesize()
    resource.setrlimit(resource.RLIMIT_AS, (size + 256 * 2 ** 20, resource.RLIM_INFINITY))
    try:
        load_config(path)
        q.put("loaded")
    except ConfigError:
        q.put("ConfigError")
    except MemoryError:
        q.put("MemoryError")


def test_a_folder_or_a_device_as_mesh_path_is_named_as_such(tmp_path):
    assert "is a folder; expected a mesh file" in error_of(tmp_path, f"input: {{mesh: {tmp_path}}}\n")
    assert "not a regular file" in error_of(tmp_path, "input: {mesh: /dev/zero}\n")
    assert "expected a file path of at most 1024" in error_of(tmp_path, "input: {mesh: " + "a" * 2000 + "}\n")


def test_shapes_refined_is_bounded_like_a_config(capsys):
    from fabricate.app.cli import main
    assert main(["shapes", "railway_station", "--refined", "--param", "nu=300", "--param", "nv=300"]) == 2
    assert f"more than {MAX_FACES:,}" in capsys.readouterr().err


def test_keys_with_control_characters_keep_the_message_on_its_lines(tmp_path):
    message = error_of(tmp_path, DOME + 'offset: {"\\x1e\\u2028": 1}\n')
    assert "offset.\\x1e\\u2028: unknown key" in message and len(message.splitlines()) == 1
    message = error_of(tmp_path, DOME + 'parts: {"a\\x1e": 1, "a\\x1e": 2}\n')
    assert "parts.a\\x1e: duplicate key" in message and len(message.splitlines()) == 1


def test_set_null_removes_the_key(tmp_path):
    path = tmp_path / "a.yaml"
    path.write_text(DOME + "parts: {beam_depth: 250}\nsubdivision: {levels: 0}\n")
    sets = parse_sets(["offset.distances=0,-200", "parts.beam_depth=null", "subdivision.levels=null"])
    cfg = load_config(path, overrides={k: v[0] for k, v in sets.items()})
    assert cfg.layer_distances() == [0.0, -200.0] and cfg.parts.beam_depth == 200.0  # the default
    assert cfg.subdivision.levels is None
