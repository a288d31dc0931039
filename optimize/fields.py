"""Option fields: a frozen dataclass field that carries what its config key needs.

:func:`option` declares a field of a frozen option object with its default and,
in the field metadata, its bounds, unit and one-line help.  It imports only the
standard library, so the optimizer's settings (:class:`optimize.options.OptimizeOptions`)
and the option objects of ``fabricate`` (which re-exports it from
``fabricate.fields``) use the same one; a configuration layer derives its keys
from the metadata (``fabricate.app.config_section.section_base``).
"""
from __future__ import annotations

from dataclasses import MISSING, field
from typing import Any


def option(default: Any = MISSING, *, unit: str = "", help: str = "", alias: str | None = None,
           ge: float | None = None, gt: float | None = None, le: float | None = None, lt: float | None = None,
           min_length: int | None = None, max_length: int | None = None, pattern: str | None = None,
           items: dict | None = None):
    """A dataclass field with what its config key needs in the metadata: bounds (``ge`` ... ``lt``,
    ``min_length`` / ``max_length``, ``pattern``), the bounds of each item of a tuple (``items``),
    the YAML name when it is not a Python name (``alias``), the unit and a one-line help."""
    given = {"unit": unit, "help": help, "alias": alias, "ge": ge, "gt": gt, "le": le, "lt": lt,
             "min_length": min_length, "max_length": max_length, "pattern": pattern, "items": items}
    meta = {k: v for k, v in given.items() if v not in (None, "")}
    return field(default=default, metadata=meta)
