"""Property suite over the config loader (issue #15, section 6).

Every input must end in a valid :class:`RunConfig` or a :class:`ConfigError`
(exit 2) whose message names the file (or ``--set``) on every line, with no
traceback and no line longer than :data:`LONGEST`, under a time cap per
input (SIGALRM) and a memory cap for the whole test (``RLIMIT_AS``: the
address space in use plus :data:`HEADROOM`).

Four classes of input:

- ``mutated``: the shipped configs with 1-3 mutations each (a value replaced by
  a hostile one, lines deleted, duplicated, swapped or re-indented, keys
  inserted, truncation, byte flips, BOM / CRLF / NUL / Latin-1 bytes, an alias
  bomb or deep nesting spliced in);
- ``generated``: YAML dumped from generated data with the schema's own keys and
  the designs' parameter names, and hostile values;
- ``text``: arbitrary short text and bytes;
- ``set``: ``--set`` items (random key paths and value texts, comma lists) on a
  shipped config, through ``fabricate.app.batch.parse_sets``.

CI runs a fixed seed and :data:`EXAMPLES` examples per class (a few seconds);
a longer campaign: ``FUZZ_CONFIG_EXAMPLES=2000 pytest -s tests/test_fuzz_config.py``
prints the figures per class (tried, valid, refused cleanly, failed).
"""
from __future__ import annotations

import inspect
import os
import resource
import signal
from collections import Counter
from contextlib import contextmanager
from pathlib import Path
from typing import get_args

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pydantic import BaseModel

from fabricate.app.batch import parse_sets
from fabricate.app.config import RunConfig, load_config
from optimize.modelling.designs import DESIGNS
from optimize.errors import ConfigError

REPO = Path(__file__).resolve().parents[1]
EXAMPLES = int(os.environ.get("FUZZ_CONFIG_EXAMPLES", "40"))
SECONDS = 10.0
"""Time cap per input (a design of the largest allowed size builds in under a second)."""
HEADROOM = 1 << 30
"""Memory cap: the address space in use when the test starts plus this (1 GiB)."""
LONGEST = 1000
"""Longest line of a message."""

SHIPPED = {p.name: p.read_text(encoding="utf-8") for p in sorted((REPO / "configs").glob("*.yaml"))
           if not p.name.startswith("halftunnel")}  # those read a mesh from outside the repository
STATS: Counter = Counter()

HOSTILE = ["0", "-1", "1e308", "-1e308", "1.0e308", ".nan", ".inf", "-.inf", "true", "off", "no", "yes", "null",
           "~", "''", "'x'", "[]", "{}", "[1, 2]", "[0, .nan]", "1e-320", "99999999999999999999999999999999",
           "0x7fffffff", "1_000", "2024-01-01", "*nope", "&a x", "!!python/none ''", "!!float nan", "é",
           '"\\u0000"', "[[[[[[]]]]]]", "a" * 5000, "300", "301", "100000", "1.5", "-0.0", "1e8", "12", "6",
           "[0, -200]", "{name: dome}", "!!binary aGVsbG8=", "!!int 0b" + "1" * 200, "? [a]", ": x", "- x", "|\n  x",
           "!!timestamp foo", "!!timestamp 99999-01-01", "!!bool maybe", "{'a[1]': 1}", "{'[x]': 1, str: 2}"]
BOMB = ('lol0: &l0 ["l","l","l","l","l","l","l","l","l"]\n'
        + "".join(f"lol{i}: &l{i} [{','.join([f'*l{i - 1}'] * 9)}]\n" for i in range(1, 9)))
SPLICES = [BOMB, "deep: " + "[" * 200 + "]" * 200 + "\n", "x: &a [*a]\n", "\ufeff", "\x00", "\t", "\r\n",
           "parts:\n  glass_thickness: 8\n", "<<: {a: 1}\n", "%YAML 1.1\n---\n", "--- \n...\n---\n"]


def _schema_keys() -> dict[str, list[str]]:
    """Top-level key -> the keys of its section ([] for a plain value)."""
    out = {}
    for name, field in RunConfig.model_fields.items():
        args = get_args(field.annotation) or (field.annotation,)
        sub = next((a for a in args if isinstance(a, type) and issubclass(a, BaseModel)), None)
        out[field.alias or name] = sub.allowed_keys() if sub is not None else []
    return out


SECTIONS = _schema_keys()
PARAMS = {name: list(inspect.signature(fn).parameters) for name, fn in DESIGNS.items()}
KEYS = sorted({k for keys in SECTIONS.values() for k in keys} | set(SECTIONS)
              | {p for ps in PARAMS.values() for p in ps})
DOTTED = sorted([s for s, keys in SECTIONS.items() if not keys]
                + [f"{s}.{k}" for s, keys in SECTIONS.items() for k in keys]
                + [f"input.shape.params.{p}" for ps in PARAMS.values() for p in ps]
                + ["input.shape.name", "parts", "a.b.c", "input.mesh.x", "parts..x"])


@pytest.fixture(scope="module", autouse=True)
def figures():
    """Print the figures per class when the module is done (shown with ``pytest -s``)."""
    yield
    classes = sorted({c for c, _ in STATS})
    print("\nconfig fuzz: class: tried, valid, refused cleanly (ConfigError), failed")
    for c in classes:
        tried = sum(n for (k, _), n in STATS.items() if k == c)
        print(f"  {c}: {tried}, {STATS[c, 'valid']}, {STATS[c, 'refused']}, {STATS[c, 'failed']}")


@pytest.fixture(scope="module")
def memory_cap():
    with open("/proc/self/statm") as fh:
        size = int(fh.read().split()[0]) * resource.getpagesize()
    old = resource.getrlimit(resource.RLIMIT_AS)
    resource.setrlimit(resource.RLIMIT_AS, (size + HEADROOM, old[1]))
    yield
    resource.setrlimit(resource.RLIMIT_AS, old)


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    """A folder for the inputs, with the shipped configs' surfaces beside them (read, never written)."""
    d = tmp_path_factory.mktemp("fuzz") / "configs"
    d.mkdir()
    (d / "surfaces").symlink_to(REPO / "configs" / "surfaces")
    return d


@contextmanager
def time_cap(seconds: float = SECONDS):
    def expire(signum, frame):
        raise TimeoutError(f"config loading still running after {seconds} s")

    old = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def check(kind: str, path: Path, data: bytes, overrides=None) -> None:
    """Load ``data`` written at ``path``: a RunConfig, or a ConfigError of clean lines."""
    path.write_bytes(data)
    outcome = "failed"
    try:
        with time_cap():
            cfg = load_config(path, overrides=overrides)
        assert isinstance(cfg, RunConfig)
        outcome = "valid"
    except ConfigError as exc:
        message = str(exc)
        lines = message.splitlines()
        assert exc.exit_code == 2 and lines, message
        assert "Traceback" not in message, message
        assert all(len(line) <= LONGEST for line in lines), message[:2000]
        assert lines[0].startswith((str(path), "--set")), message
        assert all(line.startswith(("  " + str(path), "  --set")) for line in lines[1:]), message
        outcome = "refused"
    finally:
        STATS[kind, outcome] += 1


# -- mutated shipped configs -----------------------------------------------------------
@st.composite
def mutated(draw) -> bytes:
    text = SHIPPED[draw(st.sampled_from(sorted(SHIPPED)))]
    for _ in range(draw(st.integers(1, 3))):
        lines = text.splitlines(keepends=True) or ["\n"]
        i = draw(st.integers(0, len(lines) - 1))
        op = draw(st.sampled_from(["value", "delete", "duplicate", "swap", "indent", "insert", "truncate",
                                   "flip", "splice"]))
        if op == "value" and ":" in lines[i]:
            key = lines[i].split(":", 1)[0]
            lines[i] = f"{key}: {draw(st.sampled_from(HOSTILE))}\n"
        elif op == "delete":
            del lines[i]
        elif op == "duplicate":
            lines.insert(i, lines[i])
        elif op == "swap":
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        elif op == "indent":
            lines[i] = (" " * draw(st.sampled_from([0, 1, 2, 4]))) + lines[i].lstrip(" ")
        elif op == "insert":
            lines.insert(i, " " * draw(st.sampled_from([0, 2, 4])) +
                         f"{draw(st.sampled_from(KEYS))}: {draw(st.sampled_from(HOSTILE))}\n")
        elif op == "truncate":
            text = "".join(lines)
            lines = [text[:draw(st.integers(0, len(text)))]]
        elif op == "splice":
            lines.insert(i, draw(st.sampled_from(SPLICES)))
        text = "".join(lines)
        if op == "flip" and text:
            raw = bytearray(text.encode("utf-8"))
            k = draw(st.integers(0, len(raw) - 1))
            raw[k] ^= 1 << draw(st.integers(0, 7))
            return bytes(raw)
    if draw(st.booleans()) and "é" in text:
        return text.encode("latin-1", errors="replace")
    return text.encode("utf-8")


FUZZ = settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                       HealthCheck.data_too_large])


@FUZZ
@given(data=mutated())
def test_mutated_shipped_configs(folder, memory_cap, data):
    check("mutated", folder / "mutated.yaml", data)


# -- generated YAML --------------------------------------------------------------------
SCALARS = st.one_of(st.none(), st.booleans(), st.integers(-10 ** 12, 10 ** 12), st.integers(),
                    st.floats(), st.text(max_size=12), st.sampled_from(["dome", "conical", "off", "auto", "mm",
                                                                        "surfaces/atrium_roof.obj", "../x.obj"]))
VALUES = st.recursive(SCALARS, lambda c: st.lists(c, max_size=4)
                      | st.dictionaries(st.sampled_from(KEYS) | st.text(max_size=6), c, max_size=4), max_leaves=12)


@st.composite
def generated(draw) -> bytes:
    data = {}
    for section in draw(st.lists(st.sampled_from(sorted(SECTIONS)), max_size=5, unique=True)):
        keys = SECTIONS[section]
        data[section] = draw(st.dictionaries(st.sampled_from(keys), VALUES, max_size=5)) if keys and \
            draw(st.integers(0, 4)) else draw(VALUES)
    if draw(st.integers(0, 3)):  # usually a design input, so that the other sections are reached
        name = draw(st.sampled_from(sorted(DESIGNS)))
        params = draw(st.dictionaries(st.sampled_from(PARAMS[name]), SCALARS, max_size=3))
        data["input"] = {"shape": {"name": name, "params": params}}
    text = yaml.safe_dump(data, allow_unicode=draw(st.booleans()), default_flow_style=draw(st.booleans()))
    return text.encode("utf-8")


@FUZZ
@given(data=generated())
def test_generated_configs(folder, memory_cap, data):
    check("generated", folder / "generated.yaml", data)


# -- arbitrary text and bytes ----------------------------------------------------------
@FUZZ
@given(data=st.one_of(st.binary(max_size=200), st.text(max_size=200).map(lambda t: t.encode("utf-8"))))
def test_arbitrary_text(folder, memory_cap, data):
    check("text", folder / "text.yaml", data)


# -- --set -----------------------------------------------------------------------------
GOOD = ["8", "12", "2", "0,-200", "[0, -200]", "0,-150,-300", "off", "fast", "true", "false", "conical", "pq",
        "1e-7", "0.01", "m", "boundary", "1,2,3", "keep"]
SET_TEXT = st.one_of(st.sampled_from(GOOD), st.sampled_from(HOSTILE),
                     st.lists(st.sampled_from(HOSTILE[:30]), min_size=2, max_size=4)
                     .map(",".join), st.text(min_size=1, max_size=20))


@FUZZ
@given(base=st.sampled_from(sorted(SHIPPED)),
       items=st.lists(st.tuples(st.sampled_from(DOTTED), SET_TEXT), min_size=1, max_size=2))
def test_set_overrides(folder, memory_cap, base, items):
    path = folder / "set.yaml"
    try:
        sets = parse_sets([f"{k}={v}" for k, v in items])
    except ConfigError as exc:
        assert str(exc).startswith("--set") and "\n" not in str(exc), str(exc)
        STATS["set", "refused"] += 1
        return
    sets = {k: v[0] for k, v in sets.items()}  # fabricate run's view; batch tries each value the same way
    check("set", path, SHIPPED[base].encode("utf-8"), overrides=sets)
