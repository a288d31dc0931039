"""Option fields: a frozen dataclass field that carries what its config key needs.

The frozen option objects of every stage (``fabricate.cad.spec.PartSpec``,
``fabricate.structure.options.StructureOptions``, ``fabricate.app.options``)
declare each field with :func:`option` (:func:`optimize.fields.option`, re-exported here,
the one the optimizer's settings use too): its default, bounds, unit and one-line
help.  The config sections are derived from them
(``fabricate.app.config_section.section_base``), and :func:`check_fields` holds
a constructed object to the same choices and lower bounds, so each is written
once.  This module is the bottom layer of ``fabricate``: it imports only the
standard library, :mod:`optimize.errors` and :mod:`optimize.fields`.
"""
from __future__ import annotations

import functools
import math
import types
import typing
from dataclasses import fields
from typing import Literal, get_args, get_origin

from optimize.errors import ConfigError
from optimize.fields import option  # noqa: F401 - re-exported: the option objects of fabricate use it

MAX_MM = 10_000.0
"""Largest |layer distance| and beam depth (mm): 10 m."""


def choices(annotation) -> tuple | None:
    """The values a ``Literal[...]`` (or ``Literal[...] | None``) annotation allows, else None."""
    stack, out = [annotation], []
    while stack:
        a = stack.pop(0)
        if get_origin(a) is Literal:
            out += list(get_args(a))
        elif get_origin(a) in (typing.Union, types.UnionType):
            stack += [x for x in get_args(a) if x is not type(None)]
        else:
            return None  # another type besides the words: not a choice key
    return tuple(out) or None


@functools.cache
def _rules(cls: type) -> tuple:
    hints = typing.get_type_hints(cls)
    out = []
    for f in fields(cls):
        hint = hints[f.name]
        optional = get_origin(hint) in (typing.Union, types.UnionType) and type(None) in get_args(hint)
        low = next(((b, f.metadata[b]) for b in ("gt", "ge") if b in f.metadata), None)
        integer = hint is int or (optional and int in get_args(hint))
        out.append((f.name, choices(hint), optional, low, integer, f.metadata.get("unit", "")))
    return tuple(out)


def check_fields(obj, prefix: str) -> None:
    """Hold the dataclass ``obj`` to its fields' choices (``Literal`` annotations) and lower bounds
    (``gt`` / ``ge`` of :func:`option`; an ``int`` field takes integers only; None where the
    annotation allows it).  The upper bounds are the config file's plausibility limits, applied by
    the derived config section only.  Raises ConfigError ``{prefix}.{key} = {value!r}: expected ...``."""
    for name, allowed, optional, low, integer, unit in _rules(type(obj)):
        value = getattr(obj, name)
        if value is None and optional:
            continue
        key = f"{prefix}.{name}"
        if allowed is not None:
            if value not in allowed:
                raise ConfigError(f"{key} = {value!r}: expected one of {', '.join(map(str, allowed))}")
            continue
        if low is None:
            continue
        bound, limit = low
        number = isinstance(value, int if integer else (int, float)) and not isinstance(value, bool)
        if not (number and math.isfinite(value) and (value > limit if bound == "gt" else value >= limit)):
            what = "an integer" if integer else "a number"
            units = f" ({unit})" if unit else ""
            raise ConfigError(f"{key} = {value!r}: expected {what} {'>' if bound == 'gt' else '>='} {limit:g}{units}")
