"""The base of every config section: unknown keys refused, strict types, finite numbers, YAML's
``off`` / ``on`` read as the word where a key allows the word (see :mod:`fabricate.config`)."""
from __future__ import annotations

from typing import Any, Literal, get_args, get_origin

from pydantic import BaseModel, ConfigDict, ValidationInfo, field_validator

MAX_MM = 10_000.0
"""Largest |layer distance| and beam depth (mm): 10 m."""


class Section(BaseModel):
    """A config section: unknown keys are errors (named with a did-you-mean by :func:`format_errors`),
    types are strict and numbers finite (see the module docstring)."""

    model_config = ConfigDict(extra="forbid", validate_default=True, populate_by_name=True, strict=True,
                              allow_inf_nan=False)

    @classmethod
    def allowed_keys(cls) -> list[str]:
        return [f.alias or name for name, f in cls.model_fields.items()]

    @field_validator("*", mode="before")
    @classmethod
    def _yaml_words(cls, value: Any, info: ValidationInfo) -> Any:
        """YAML's ``off`` / ``no`` (false) and ``on`` / ``yes`` (true) as the word, for a key that
        allows the word and not a boolean."""
        if isinstance(value, bool):
            words = _bool_words(cls.model_fields[info.field_name].annotation)
            if words is not None:
                return words[value] if words[value] is not None else value
        return value


_FALSE, _TRUE = ("off", "no", "false"), ("on", "yes", "true")


def _bool_words(annotation) -> dict[bool, str | None] | None:
    """``{False: "off", True: None}`` for a Literal annotation allowing those words and no bool."""
    words: list[str] = []
    stack = [annotation]
    while stack:
        a = stack.pop()
        if a is bool:
            return None
        if get_origin(a) is Literal:
            words += [w for w in get_args(a) if isinstance(w, str)]
        else:
            stack.extend(get_args(a))
    pick = {False: next((w for w in _FALSE if w in words), None), True: next((w for w in _TRUE if w in words), None)}
    return pick if any(pick.values()) else None
