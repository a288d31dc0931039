"""Config error messages: ``file:line: key.path: value ...: what is allowed``.

Turns a pydantic ``ValidationError`` into one line per problem (sorted by
line), naming the YAML line of the key (from :mod:`fabricate.app.config_yaml`),
the dotted key path, the value given (cut to :data:`SHORT` characters), what
is allowed (a number key's range, from its schema field: :func:`field_range`),
and a did-you-mean (difflib) for misspelt keys and choices.
"""
from __future__ import annotations

import difflib
import re
from pathlib import Path
from typing import Any, get_args, get_origin

import annotated_types as at
from pydantic import BaseModel, ValidationError

SHORT = 60
"""Longest value repr quoted in a message (longer ones are cut with '...')."""


def short(value: Any, limit: int = SHORT) -> str:
    """``repr(value)``, cut to ``limit`` characters (a message quotes a value, not a file)."""
    text = repr(value) if len(str(value)) <= 4 * limit else repr(str(value)[:limit])
    return text if len(text) <= limit else text[:limit - 3] + "..."


def printable(text: str) -> str:
    """``text`` with every character that would break or hide a line escaped (``\\x1e``, ``\\u2028``)."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in text)


def did_you_mean(word: str, allowed) -> str:
    """``" (did you mean 'x'?)"`` for the closest of ``allowed``, or ``""``."""
    if len(str(word)) > 100:
        return ""
    close = difflib.get_close_matches(str(word), [str(a) for a in allowed], n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _clean_loc(loc: tuple, data: Any = None) -> tuple:
    """Drop pydantic's union tags (``'list[int]'``, ``'literal[...]'``, ``'str'``) from a location.

    A part is a key of the file when ``data`` (the validated input) has it at that place: a key
    written ``foo[1]`` or ``str`` stays; a part that is no key there is a tag."""
    tags = {"str", "int", "float", "bool", "none"}
    out, node = [], data
    for p in loc:
        if isinstance(node, dict) and p in node:
            node = node[p]
        elif isinstance(node, (list, tuple)) and isinstance(p, int) and -len(node) <= p < len(node):
            node = node[p]
        elif isinstance(p, int) or ("[" not in p and p not in tags):
            node = None  # beyond the data (a key pydantic adds, a default): the old rule
        else:
            continue
        out.append(p)
    return tuple(out)


def _section_at(root: type[BaseModel], loc: tuple) -> type[BaseModel] | None:
    """The model class (config section) that holds the keys at ``loc`` (a key path), or None."""
    cls = root
    for key in loc:
        field = cls.model_fields.get(key) if isinstance(key, str) else None
        if field is None:
            field = next((f for f in cls.model_fields.values() if f.alias == key), None)
        if field is None:
            return None
        sub = _sections_in(field.annotation)
        if sub is None:
            return None
        cls = sub
    return cls


def _sections_in(annotation) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in get_args(annotation):
        found = _sections_in(arg)
        if found is not None:
            return found
    return None


def format_errors(exc: ValidationError, source: Path, lines: dict[tuple, int],
                  overrides: dict[str, Any], root: type[BaseModel], data: Any = None) -> str:
    """All problems, one per line: ``file:line: key.path: value ...: what is allowed`` (``data``: the
    input validated, which tells the file's keys from pydantic's tags in a location)."""
    messages, seen = [], set()
    errors = [dict(e, loc=_clean_loc(e["loc"], data)) for e in exc.errors(include_url=False)]
    for err in errors:
        loc = err["loc"]
        key = printable(".".join(str(p) for p in loc)) or "(top level)"
        param = (err.get("ctx") or {}).get("param")
        at = loc + ("params", param) if param else loc  # a design parameter: its own line
        if key in seen:  # one message per key (a union reports each alternative)
            continue
        if err["type"] == "literal_error" and any(
                len(e["loc"]) > len(loc) and e["loc"][:len(loc)] == loc for e in errors):
            continue  # a list given where a word or a list is allowed: the list's error says more
        seen.add(key)
        line = next((lines[at[:i]] for i in range(len(at), 0, -1) if at[:i] in lines), None)
        where = f"{source}:{line}" if line else str(source)
        via = next((f" (from --set {k}={short(v)})" for k, v in overrides.items()
                    if tuple(k.split(".")) == loc[:len(k.split("."))]), "")
        messages.append((line or 0, printable(f"{where}: {key}: {_message(err, loc, root)}{via}")))
    messages = [m for _, m in sorted(messages, key=lambda m: m[0])]
    if len(messages) == 1:
        return messages[0]
    return f"{source}: {len(messages)} problems:\n  " + "\n  ".join(messages)


def _message(err: dict, loc: tuple, root: type[BaseModel]) -> str:
    kind, msg, value = err["type"], err["msg"], err.get("input")
    if kind == "extra_forbidden" and loc:
        section = _section_at(root, loc[:-1])
        allowed = [f.alias or name for name, f in section.model_fields.items()] if section else []
        return (f"unknown key{did_you_mean(loc[-1], allowed)}"
                + (f"; allowed: {', '.join(allowed)}" if allowed else ""))
    if kind == "missing":
        return "required key is missing"
    if kind == "string_pattern_mismatch":
        return f"value {short(value)}: expected letters, digits and _ . = + - only (it names a folder)"
    if kind == "literal_error":
        expected = err.get("ctx", {}).get("expected", "")
        return f"value {short(value)} is not allowed{did_you_mean(value, _literal_values(expected))}; " \
               f"expected one of {expected}"
    for a, b in (("Input should be", "expected"), ("List should have", "expected"),
                 ("Value error, ", ""), (" after validation", "")):
        msg = msg.replace(a, b)
    msg = re.sub(r" or instance of \w+", "", msg)  # pydantic's words for a section given as a value
    allowed = field_range(root, loc)
    if allowed and kind in _RANGE_ERRORS:
        msg = f"expected {allowed}{field_unit(root, loc)}"
    if kind in ("int_type", "float_type", "bool_type") and isinstance(value, (bool, str)):
        msg += f" (YAML reads {short(value)} as a {'string' if isinstance(value, str) else 'boolean'}" + (
            ")" if kind == "bool_type" else ", not a number)")
    if isinstance(value, dict) or (isinstance(value, list) and kind not in ("too_short", "too_long")):
        return msg
    return f"value {short(value)}: {msg}"


_RANGE_ERRORS = {"greater_than", "greater_than_equal", "less_than", "less_than_equal", "finite_number",
                 "int_type", "float_type", "int_parsing", "float_parsing"}


def field_range(root: type[BaseModel], loc: tuple) -> str | None:
    """``"6..256"`` / ``"(0, 200]"`` for the number key at ``loc`` (a list item: its list's items), or None."""
    field = _field_at(root, loc)
    if field is None:
        return None
    metadata = list(field.metadata)
    if isinstance(loc[-1], int):  # an item: the bounds of the list's item type
        metadata = [m for a in _annotations(field.annotation) for m in getattr(a, "__metadata__", ())]
        metadata += [m for a in _annotations(field.annotation) for m in getattr(a, "metadata", ())]
    lo = next(((m.ge, "[") for m in metadata if isinstance(m, at.Ge)), None) or \
        next(((m.gt, "(") for m in metadata if isinstance(m, at.Gt)), None)
    hi = next(((m.le, "]") for m in metadata if isinstance(m, at.Le)), None) or \
        next(((m.lt, ")") for m in metadata if isinstance(m, at.Lt)), None)
    if lo is None and hi is None:
        return None
    integer = int in _annotations(field.annotation)
    if integer and lo and hi and lo[1] == "[" and hi[1] == "]":
        return f"an integer in {number(lo[0])}..{number(hi[0])}"
    left = f"{lo[1]}{number(lo[0])}" if lo else "(-inf"
    right = f"{number(hi[0])}{hi[1]}" if hi else "inf)"
    return f"{'an integer' if integer else 'a number'} in {left}, {right}"


def field_unit(root: type[BaseModel], loc: tuple) -> str:
    """``" mm"`` for a key at ``loc`` whose field names its unit (``json_schema_extra``), else ``""``."""
    field = _field_at(root, loc)
    extra = getattr(field, "json_schema_extra", None)
    return f" {extra['unit']}" if isinstance(extra, dict) and extra.get("unit") else ""


def _field_at(root: type[BaseModel], loc: tuple):
    """The schema field of the key at ``loc`` (list indices skipped), or None."""
    keys = tuple(p for p in loc if isinstance(p, str))
    section = _section_at(root, keys[:-1]) if keys else None
    if section is None:
        return None
    return section.model_fields.get(keys[-1]) or next(
        (f for f in section.model_fields.values() if f.alias == keys[-1]), None)


def number(x: float) -> str:
    """``1e-12``, ``1e6``, ``200``: a bound as a person writes it."""
    return f"{x:g}".replace("e+0", "e").replace("e+", "e").replace("e-0", "e-")


def _annotations(annotation) -> list:
    out, stack = [], [annotation]
    while stack:
        a = stack.pop()
        out.append(a)
        if get_origin(a) is not None or getattr(a, "__metadata__", None):
            stack.extend(get_args(a))
    return out


def _literal_values(expected: str) -> list[str]:
    return [p.strip(" '\"") for p in expected.replace(" or ", ",").split(",") if p.strip(" '\"")]
