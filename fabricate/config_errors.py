"""Config error messages: ``file:line: key.path: value ...: what is allowed``.

Turns a pydantic ``ValidationError`` into one line per problem (sorted by
line), naming the YAML line of the key (found with ``yaml.compose``: the node
tree only, no objects are built), the dotted key path, the value given, what
is allowed, and a did-you-mean (difflib) for misspelt keys and choices.
"""
from __future__ import annotations

import difflib
from pathlib import Path
from typing import Any, get_args

import yaml
from pydantic import BaseModel, ValidationError


def did_you_mean(word: str, allowed) -> str:
    """``" (did you mean 'x'?)"`` for the closest of ``allowed``, or ``""``."""
    close = difflib.get_close_matches(str(word), [str(a) for a in allowed], n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def key_lines(text: str) -> dict[tuple, int]:
    """Map key paths to 1-based line numbers (from the YAML node tree; no objects built)."""
    out: dict[tuple, int] = {}
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError:
        return out

    def walk(node, path):
        if isinstance(node, yaml.MappingNode):
            for k, v in node.value:
                key = path + (k.value,)
                out[key] = k.start_mark.line + 1
                walk(v, key)
        elif isinstance(node, yaml.SequenceNode):
            for i, v in enumerate(node.value):
                out[path + (i,)] = v.start_mark.line + 1
                walk(v, path + (i,))

    if root is not None:
        walk(root, ())
    return out


def _clean_loc(loc: tuple) -> tuple:
    """Drop pydantic's union tags (``'list[int]'``, ``'literal[...]'``, ``'str'``) from a location."""
    tags = {"str", "int", "float", "bool", "none"}
    return tuple(p for p in loc if isinstance(p, int) or ("[" not in p and p not in tags))


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
                  overrides: dict[str, Any], root: type[BaseModel]) -> str:
    """All problems, one per line: ``file:line: key.path: value ...: what is allowed``."""
    messages, seen = [], set()
    errors = [dict(e, loc=_clean_loc(e["loc"])) for e in exc.errors(include_url=False)]
    for err in errors:
        loc = err["loc"]
        key = ".".join(str(p) for p in loc) or "(top level)"
        if key in seen:  # one message per key (a union reports each alternative)
            continue
        if err["type"] == "literal_error" and any(
                len(e["loc"]) > len(loc) and e["loc"][:len(loc)] == loc for e in errors):
            continue  # a list given where a word or a list is allowed: the list's error says more
        seen.add(key)
        line = next((lines[loc[:i]] for i in range(len(loc), 0, -1) if loc[:i] in lines), None)
        where = f"{source}:{line}" if line else str(source)
        via = next((f" (from --set {k}={v!r})" for k, v in overrides.items()
                    if tuple(k.split(".")) == loc[:len(k.split("."))]), "")
        messages.append((line or 0, f"{where}: {key}: {_message(err, loc, root)}{via}"))
    messages = [m for _, m in sorted(messages, key=lambda m: m[0])]
    if len(messages) == 1:
        return messages[0]
    return f"{source}: {len(messages)} problems:\n  " + "\n  ".join(messages)


def _message(err: dict, loc: tuple, root: type[BaseModel]) -> str:
    kind, msg, value = err["type"], err["msg"], err.get("input")
    if kind == "extra_forbidden":
        section = _section_at(root, loc[:-1])
        allowed = [f.alias or name for name, f in section.model_fields.items()] if section else []
        return (f"unknown key{did_you_mean(loc[-1], allowed)}"
                + (f"; allowed: {', '.join(allowed)}" if allowed else ""))
    if kind == "missing":
        return "required key is missing"
    if kind == "string_pattern_mismatch":
        return f"value {value!r}: expected letters, digits and _ . = + - only (it names a folder)"
    if kind == "literal_error":
        expected = err.get("ctx", {}).get("expected", "")
        return f"value {value!r} is not allowed{did_you_mean(value, _literal_values(expected))}; " \
               f"expected one of {expected}"
    for a, b in (("Input should be", "expected"), ("List should have", "expected"),
                 ("Value error, ", ""), (" after validation", "")):
        msg = msg.replace(a, b)
    if isinstance(value, dict) or (isinstance(value, list) and kind not in ("too_short", "too_long")):
        return msg
    return f"value {value!r}: {msg}"


def _literal_values(expected: str) -> list[str]:
    return [p.strip(" '\"") for p in expected.replace(" or ", ",").split(",") if p.strip(" '\"")]
