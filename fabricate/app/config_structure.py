"""The ``structure`` config section, derived from the structure stage's frozen options
(:mod:`fabricate.structure.options`: defaults, bounds, help); here only what a YAML file adds:
strict types, lists for tuples, and the checks that name a key.  :meth:`StructureSection.to_options`
gives the :class:`~fabricate.structure.options.StructureOptions` the stage takes."""
from __future__ import annotations

from pydantic import Field, field_validator, model_validator
from pydantic_core import PydanticCustomError

from ..structure.options import (
    CombinationOptions,
    LoadsOptions,
    SectionOptions,
    SizingOptions,
    StructureOptions,
)
from .config_section import section_base


class SectionOption(section_base(SectionOptions)):
    """A beam section (mm); defaults and bounds: :class:`fabricate.structure.options.SectionOptions`."""

    @model_validator(mode="after")
    def _valid(self) -> SectionOption:
        from optimize.errors import ConfigError

        try:
            self.to_options().properties()
        except ConfigError as exc:
            raise PydanticCustomError("section", "{err}", {"err": str(exc)}) from None
        return self


class LoadsOption(section_base(LoadsOptions)):
    """The ``structure.loads`` section (defaults: :class:`fabricate.structure.options.LoadsOptions`)."""


class CombinationOption(section_base(CombinationOptions)):
    """One combination: ``name``, ``kind`` (``uls`` strength, ``sls`` deflection), factors per case."""

    @field_validator("factors")
    @classmethod
    def _factors(cls, v):
        bad = {k: f for k, f in v.items() if not (f >= 0)}
        if bad:
            k, f = next(iter(bad.items()))
            raise PydanticCustomError("factor", "factor {k} = {f}: expected a number >= 0 (a partial factor times "
                                      "a combination factor)", {"k": k, "f": f})
        if not v:
            raise PydanticCustomError("factor", "no factors, expected at least one load case")
        return v


class SizingOption(section_base(SizingOptions, extra={
        "sections": (list[SectionOption], Field(default_factory=list))})):
    """``fabricate size``: candidate sections (lightest passing one per group) and the grouping."""


_NESTED = {
    "section": (SectionOption | None, Field(default=None)),  # null: the section the parts are welded from (parts.beam)
    "loads": (LoadsOption, Field(default_factory=LoadsOption)),
    "combinations": (list[CombinationOption] | None, Field(default=None)),  # null: DEFAULT_COMBINATIONS
    "sizing": (SizingOption, Field(default_factory=SizingOption)),
}


class StructureSection(section_base(StructureOptions, extra=_NESTED)):
    """The structural check of the beam frame (``fabricate.structure``); ``check: off`` skips it
    (defaults: :class:`fabricate.structure.options.StructureOptions`)."""

    @field_validator("supports")
    @classmethod
    def _supports(cls, v):
        if isinstance(v, list):
            if not v:
                raise PydanticCustomError("supports", "an empty list supports nothing; expected vertex indices, "
                                          "'lowest', 'boundary' or 'outline'")
            if any(i < 0 for i in v):
                raise PydanticCustomError("supports", "vertex indices must be >= 0")
        return v

    @field_validator("up")
    @classmethod
    def _up(cls, v):
        if sum(c * c for c in v) <= 0:
            raise PydanticCustomError("up", "up {v} is not a nonzero vector, expected [x, y, z]", {"v": list(v)})
        return v

