"""The base of every config section: unknown keys refused, strict types, finite numbers, YAML's
``off`` / ``on`` read as the word where a key allows the word (see :mod:`fabricate.app.config`);
:func:`section_base` derives a section from a frozen option object (:mod:`fabricate.app.options`)."""
from __future__ import annotations

import dataclasses
import types
import typing
from typing import Annotated, Any, Literal, get_args, get_origin

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, create_model, field_validator

from .options import MAX_MM  # noqa: F401 - re-exported


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

    def to_options(self):
        """The frozen option object this section was derived from, with this section's values
        (:func:`section_base`; lists become tuples)."""
        cls = next((OPTIONS[c] for c in type(self).__mro__ if c in OPTIONS), None)
        if cls is None:
            raise TypeError(f"{type(self).__name__} is not derived from an option object")
        return cls(**{f.name: _frozen_value(getattr(self, f.name)) for f in dataclasses.fields(cls)})


OPTIONS: dict[type, type] = {}
"""Section class made by :func:`section_base` -> the option class it comes from."""

_BOUNDS = ("ge", "gt", "le", "lt", "min_length", "max_length", "pattern", "alias")


def section_base(options: type, *, meta: dict[str, dict] | None = None, extra: dict[str, tuple] | None = None,
                 order: typing.Sequence[str] | None = None) -> type[Section]:
    """A :class:`Section` whose keys are the fields of the frozen dataclass ``options``: each key's
    default is the field's, its bounds, alias, unit and help those of the field metadata
    (:func:`optimize.fields.option`; ``meta`` adds to it by field name, for an option class that has
    none, like :class:`optimize.tolerances.Tolerances`).  A ``tuple[X, ...]`` field is a YAML list
    (with ``items`` bounds on each item).  ``extra``: further keys ``{name: (annotation, Field)}`` of
    the section only (nested sections, or a field's key as the section has it); ``order``: the order of
    the keys (a field it leaves out is no key of the section).  Subclass the result to add
    validators and methods; :meth:`Section.to_options` gives the option object back."""
    hints = typing.get_type_hints(options)
    fields: dict[str, tuple] = {}
    for f in dataclasses.fields(options):
        md = {**f.metadata, **(meta or {}).get(f.name, {})}
        annotation = _schema_type(hints[f.name], md.get("items"))
        default = (f.default if f.default is not dataclasses.MISSING
                   else ... if f.default_factory is dataclasses.MISSING  # ...: a required key
                   else f.default_factory())
        help_ = md.get("help", "") + (f" ({md['unit']})" if md.get("unit") else "")
        if annotation is not hints[f.name] and isinstance(default, tuple):
            default = list(default)  # the default of a YAML list
        fields[f.name] = (annotation, Field(default=default, description=help_ or None,
                                            json_schema_extra={"unit": md["unit"]} if md.get("unit") else None,
                                            **{k: md[k] for k in _BOUNDS if k in md}))
    fixed = [f.name for f in dataclasses.fields(options) if _fixed_tuple(hints[f.name]) and f.name not in (extra or {})]
    fields.update(extra or {})
    if order is not None:
        fields = {k: fields[k] for k in order}
    model = create_model(f"{options.__name__}Keys", __base__=Section, __module__=__name__,
                         __validators__={"_yaml_tuples": tuples(*fixed)} if fixed else None, **fields)
    OPTIONS[model] = options
    return model


def _schema_type(annotation, items: dict | None):
    """``tuple[X, ...]`` -> ``list[X]`` (YAML lists; ``items`` bounds on X); ``items`` bounds each
    item of a fixed ``tuple[X, Y]`` too; elsewhere unchanged."""
    origin, args = get_origin(annotation), get_args(annotation)
    if origin in (typing.Union, types.UnionType):
        return typing.Union[tuple(_schema_type(a, items) for a in args)]
    if origin is tuple and len(args) == 2 and args[1] is Ellipsis:
        item = Annotated[args[0], Field(**items)] if items else args[0]
        return list[item]
    if origin is tuple and items:
        return tuple[tuple(Annotated[a, Field(**items)] for a in args)]
    return annotation


def tuples(*names: str):
    """A before-validator that takes a YAML list given to the tuple keys ``names`` as the tuple
    (strict types refuse a list for a tuple).  :func:`section_base` adds it to every fixed-length
    tuple field by itself."""
    return field_validator(*names, mode="before")(_as_tuple)


def _as_tuple(value):
    return tuple(value) if isinstance(value, list) else value


def _fixed_tuple(annotation) -> bool:
    """Whether ``annotation`` is, or has in a union, a fixed-length ``tuple[X, Y, ...]``."""
    origin, args = get_origin(annotation), get_args(annotation)
    if origin in (typing.Union, types.UnionType):
        return any(_fixed_tuple(a) for a in args)
    return origin is tuple and not (len(args) == 2 and args[1] is Ellipsis)


def _frozen_value(value):
    """A section's value as its option object takes it: a nested derived section as its option
    object, another section as its dict, a list as a tuple."""
    if isinstance(value, Section):
        return value.to_options() if any(c in OPTIONS for c in type(value).__mro__) else value.model_dump()
    return tuple(_frozen_value(v) for v in value) if isinstance(value, list) else value


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
