"""The config file reader: YAML to plain data, strict and bounded.

``read_config(path) -> (data, lines)`` reads a run configuration in bounded
time and memory whatever the file holds, or raises
:class:`optimize.errors.ConfigError` with one line naming the file, the line
and what is wrong:

- at most :data:`MAX_BYTES` bytes (read no further: a huge file or a device
  costs nothing), UTF-8 text (a BOM is allowed; Latin-1 and other encodings are
  refused naming the line of the first bad byte);
- ``yaml.SafeLoader`` underneath (no tags that build Python objects), with
  numbers read the YAML 1.2 way: ``1e-6`` is a number (YAML 1.1 reads it as a
  string), ``010`` and ``1:30`` are not (1.1 reads octal and base 60), dates
  stay strings, integers have at most 30 digits;
- nesting at most :data:`MAX_DEPTH` levels (checked while composing, so a
  deeply nested file never reaches Python's recursion limit);
- aliases (``&a`` / ``*a``) are allowed while the document they expand to
  holds at most :data:`MAX_NODES` values; a "billion laughs" file is refused
  after visiting that many nodes, naming the line of the alias.  Aliases are
  kept (not refused outright) because repeating a block with ``*a`` or ``<<: *a``
  is ordinary YAML and costs nothing within the budget;
- a key given twice in one mapping is refused, naming both lines (YAML
  itself lets the last one win silently).

``lines`` maps key paths (tuples of keys and list indices) to 1-based lines.
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml
from yaml.resolver import Resolver

from optimize.errors import ConfigError

from .config_errors import printable, short

MAX_BYTES = 1 << 20
"""Largest config file read (1 MiB; the longest shipped config is about 6 kB)."""
MAX_DEPTH = 32
"""Deepest nesting of mappings and lists (a run config nests 4 levels)."""
MAX_NODES = 100_000
"""Most values (keys, scalars, lists, mappings) a config may hold once its aliases are expanded."""

_INT, _FLOAT = "tag:yaml.org,2002:int", "tag:yaml.org,2002:float"
_DROP = {_INT, _FLOAT, "tag:yaml.org,2002:timestamp", "tag:yaml.org,2002:value"}
_MERGE = "tag:yaml.org,2002:merge"


class _Resolver(Resolver):
    """YAML 1.1 booleans and nulls (``off`` is false), YAML 1.2 numbers, no dates."""


_Resolver.yaml_implicit_resolvers = {
    first: [(tag, rx) for tag, rx in pairs if tag not in _DROP]
    for first, pairs in Resolver.yaml_implicit_resolvers.items()}
_Resolver.add_implicit_resolver(_INT, re.compile(r"^[-+]?(0|[1-9][0-9_]{0,29})$|^0x[0-9a-fA-F_]{1,30}$"),
                                list("-+0123456789"))
_Resolver.add_implicit_resolver(
    _FLOAT, re.compile(r"""^[-+]?(?:[0-9][0-9_]*\.[0-9_]*|\.[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)?$
                        |^[-+]?[0-9][0-9_]*[eE][-+]?[0-9]+$
                        |^[-+]?\.(?:inf|Inf|INF)$|^\.(?:nan|NaN|NAN)$""", re.X),
    list("-+0123456789."))


class _Loader(yaml.reader.Reader, yaml.scanner.Scanner, yaml.parser.Parser, yaml.composer.Composer,
              yaml.constructor.SafeConstructor, _Resolver):
    """SafeLoader with :class:`_Resolver` and a nesting limit while composing."""

    def __init__(self, stream: str, where: str):
        yaml.reader.Reader.__init__(self, stream)
        yaml.scanner.Scanner.__init__(self)
        yaml.parser.Parser.__init__(self)
        yaml.composer.Composer.__init__(self)
        yaml.constructor.SafeConstructor.__init__(self)
        _Resolver.__init__(self)
        self._where, self._depth = where, 0

    def compose_node(self, parent, index):
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                line = self.peek_event().start_mark.line + 1
                raise ConfigError(f"{self._where}:{line}: nested deeper than {MAX_DEPTH} levels; "
                                  "expected a config of sections and keys (4 levels)")
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_object(self, node, deep=False):
        """A node's value; a scalar its explicit tag cannot take (``!!timestamp foo``, ``!!bool maybe``)
        is a ConfigError naming its line, tag and value (PyYAML raises anything from ValueError to
        AttributeError for them)."""
        try:
            return super().construct_object(node, deep)
        except (yaml.YAMLError, ConfigError, RecursionError, MemoryError):
            raise
        except Exception as exc:  # noqa: BLE001 - every constructor failure is a bad value in the file
            raise ConfigError(_tag_message(node, self._where, exc)) from None


_TAG_EXPECTS = {"timestamp": "a date such as 2024-05-01 or 2024-05-01T12:30:00Z", "bool": "true or false",
                "int": "an integer", "float": "a number", "binary": "base64 text", "null": "null or ~"}


def _tag_message(node, where: str, exc: Exception) -> str:
    """``file:line: not valid YAML: !!timestamp 'foo' cannot be read ...; expected ...`` (a node its tag
    cannot build)."""
    tag = str(node.tag).rsplit(":", 1)[-1]
    value = short(node.value) if isinstance(node, yaml.ScalarNode) else type(node).__name__
    expect = _TAG_EXPECTS.get(tag, f"a value the !!{tag} tag reads")
    reason = f" ({_one_line(str(exc))})" if isinstance(exc, (ValueError, OverflowError)) and str(exc) else ""
    return printable(f"{where}:{node.start_mark.line + 1}: not valid YAML: !!{tag} {value} cannot be read as "
                     f"a {tag}{reason}; expected {expect}, or the value without the tag")


def decode(raw: bytes, where: str) -> str:
    """UTF-8 text of ``raw`` (a leading BOM dropped); ConfigError naming the line of a bad byte."""
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        col = exc.start - (raw.rfind(b"\n", 0, exc.start) + 1) + 1
        raise ConfigError(f"{where}:{line}: not UTF-8 text (byte 0x{raw[exc.start]:02X} at column {col}); "
                          "expected a UTF-8 file: save it as UTF-8 (Latin-1 and other encodings are not read)") \
            from None


def read_config(path: str | Path) -> tuple[Any, dict[tuple, int]]:
    """``(data, lines)`` of the YAML file ``path`` (see the module docstring for the limits)."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            raw = fh.read(MAX_BYTES + 1)
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read the config file ({exc.strerror or exc})") from None
    if len(raw) > MAX_BYTES:
        raise ConfigError(f"{path}: larger than {MAX_BYTES // 1024} KiB, the largest config read; "
                          "expected a YAML run configuration (a few kB)")
    return load_yaml(decode(raw, str(path)), str(path))


def load_yaml(text: str, where: str) -> tuple[Any, dict[tuple, int]]:
    """``(data, lines)`` of YAML ``text``; ``where`` names it in messages (a file, ``--set``)."""
    if len(text) > MAX_BYTES:
        raise ConfigError(f"{where}: longer than {MAX_BYTES // 1024} KiB, the largest config read")
    loader = None
    try:
        loader = _Loader(text, where)
        root = loader.get_single_node()
        lines = _check_tree(root, where)
        data = loader.construct_document(root) if root is not None else None
    except yaml.YAMLError as exc:
        raise ConfigError(_yaml_message(exc, where, text)) from None
    except (ValueError, TypeError, OverflowError) as exc:  # a scalar the constructor cannot convert
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(f"{where}: not valid YAML: {_one_line(str(exc))}") from None
    finally:
        if loader is not None:
            loader.dispose()
    return data, lines


def _check_tree(root, where: str) -> dict[tuple, int]:
    """Walk the node tree as expanded (aliases followed), at most MAX_NODES nodes: key lines,
    duplicate keys, nesting depth."""
    lines: dict[tuple, int] = {}
    if root is None:
        return lines
    stack = [(root, (), 1)]
    count = 0
    while stack:
        node, path, depth = stack.pop()
        count += 1
        if count > MAX_NODES:
            raise ConfigError(f"{where}:{node.start_mark.line + 1}: more than {MAX_NODES:,} values once its "
                              "aliases (*name) are expanded; expected a run configuration (aliases that "
                              "repeat other aliases multiply: a 'billion laughs' file is refused)")
        if depth > MAX_DEPTH:
            raise ConfigError(f"{where}:{node.start_mark.line + 1}: nested deeper than {MAX_DEPTH} levels once "
                              "its aliases are expanded (an alias inside its own anchor?); expected a config "
                              "of sections and keys")
        if isinstance(node, yaml.MappingNode):
            seen: dict[tuple, int] = {}
            for k, v in node.value:
                line = k.start_mark.line + 1
                if isinstance(k, yaml.ScalarNode) and k.tag != _MERGE:
                    ident = (k.tag, k.value)
                    if ident in seen:
                        name = printable(".".join(str(p) for p in path + (k.value,)))
                        raise ConfigError(f"{where}:{line}: {name}: duplicate key (also at line {seen[ident]}); "
                                          "expected each key once per section (YAML would keep the last "
                                          "silently)")
                    seen[ident] = line
                    lines.setdefault(path + (k.value,), line)
                    stack.append((v, path + (k.value,), depth + 1))
                else:
                    stack.append((k, path, depth + 1))
                    stack.append((v, path, depth + 1))
        elif isinstance(node, yaml.SequenceNode):
            for i, v in enumerate(node.value):
                lines.setdefault(path + (i,), v.start_mark.line + 1)
                stack.append((v, path + (i,), depth + 1))
    return lines


def _one_line(text: str) -> str:
    return printable(" ".join(text.split())[:300])


def _yaml_message(exc: yaml.YAMLError, where: str, text: str) -> str:
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    line = f":{mark.line + 1}" if mark is not None else ""
    if isinstance(exc, yaml.reader.ReaderError):
        char = exc.character if isinstance(exc.character, int) else ord(exc.character[:1] or "?")
        problem = f"character U+{char:04X} is not allowed in YAML ({exc.reason})"
        line = f":{text.count(chr(10), 0, exc.position or 0) + 1}"
    else:
        problem = getattr(exc, "problem", None) or str(exc)
        context = getattr(exc, "context", None)
        if context and "constructor" in problem:
            problem = f"{context}: {problem}"
    return printable(f"{where}{line}: not valid YAML: {_one_line(problem)}")


def parse_value(text: str) -> Any:
    """A ``--set`` value read as YAML (``8`` -> 8, ``1e-6`` -> 1e-06, ``off`` -> False,
    ``[0, -200]`` -> a list); text that is not YAML stays the text."""
    if not text.strip():
        return ""
    try:
        data, _ = load_yaml(text, "--set")
    except ConfigError:
        return text
    return data
