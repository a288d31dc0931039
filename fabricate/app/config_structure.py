"""The ``structure`` config section, derived from the structure stage's frozen options
(:mod:`fabricate.structure.options`: defaults, bounds, help); here only what a YAML file adds:
strict types, lists for tuples, and the checks that name a key.  :meth:`StructureSection.to_options`
gives the :class:`~fabricate.structure.options.StructureOptions` the stage takes."""
from __future__ import annotations

import math

from pydantic import Field, field_validator, model_validator
from pydantic_core import PydanticCustomError

from ..structure.options import (
    CombinationOptions,
    LoadsOptions,
    SectionOptions,
    SizingOptions,
    StructureOptions,
)
from ..structure.glass import GlassOptions
from .config_section import MAX_MM, section_base


_SIZES = {k: {"le": MAX_MM} for k in ("depth", "width", "web", "flange")}
"""The plausibility bound of a section's dimensions (MAX_MM, 10 m; past it the section properties overflow)."""
MAX_AREA_LOAD = 100.0
"""Largest area load (kN/m2): ten times a heavy design snow load."""
MAX_UNIT_WEIGHT = 1000.0
"""Largest unit weight (kN/m3): steel is 78.5, the densest metal about 220."""
MAX_TEMPERATURE = 200.0
"""Largest uniform temperature change (K)."""
MAX_FACTOR = 10.0
"""Largest factor of a load case in a combination (EN 1990's are at most 1.5)."""
_LOADS = {"steel_unit_weight": {"le": MAX_UNIT_WEIGHT}, "glass_unit_weight": {"le": MAX_UNIT_WEIGHT},
          "temperature": {"le": MAX_TEMPERATURE},
          **{k: {"le": MAX_AREA_LOAD} for k in ("finishes", "snow", "wind_pressure", "wind_suction", "maintenance")}}


class SectionOption(section_base(SectionOptions, meta=_SIZES)):
    """A beam section (mm); defaults and bounds: :class:`fabricate.structure.options.SectionOptions`
    (upper bounds: the config's plausibility limit :data:`MAX_MM`)."""

    @model_validator(mode="after")
    def _valid(self) -> SectionOption:
        from optimize.errors import ConfigError

        try:
            self.to_options().properties()
        except ConfigError as exc:
            raise PydanticCustomError("section", "{err}", {"err": str(exc)}) from None
        return self


class LoadsOption(section_base(LoadsOptions, meta=_LOADS)):
    """The ``structure.loads`` section (defaults: :class:`fabricate.structure.options.LoadsOptions`;
    upper bounds :data:`MAX_AREA_LOAD`, :data:`MAX_UNIT_WEIGHT`)."""


class CombinationOption(section_base(CombinationOptions)):
    """One combination: ``name``, ``kind`` (``uls`` strength, ``sls`` deflection), factors per case."""

    @field_validator("factors")
    @classmethod
    def _factors(cls, v):
        bad = {k: f for k, f in v.items() if not (0 <= f <= MAX_FACTOR)}
        if bad:
            k, f = next(iter(bad.items()))
            raise PydanticCustomError("factor", "factor {k} = {f}: expected a number in [0, {top}] (a partial factor "
                                      "times a combination factor)", {"k": k, "f": f, "top": f"{MAX_FACTOR:g}"})
        if not v:
            raise PydanticCustomError("factor", "no factors, expected at least one load case")
        return v


class SizingOption(section_base(SizingOptions, extra={
        "sections": (list[SectionOption], Field(default_factory=list))})):
    """``fabricate size``: candidate sections (lightest passing one per group) and the grouping."""


class GlassOption(section_base(GlassOptions)):
    """``structure.glass``: the glass check of every panel (EN 16612; defaults:
    :class:`fabricate.structure.glass.GlassOptions`)."""


_NESTED = {
    "section": (SectionOption | None, Field(default=None)),  # null: the section the parts are welded from (parts.beam)
    "loads": (LoadsOption, Field(default_factory=LoadsOption)),
    "combinations": (list[CombinationOption] | None, Field(default=None)),  # null: DEFAULT_COMBINATIONS
    "sizing": (SizingOption, Field(default_factory=SizingOption)),
    "glass": (GlassOption, Field(default_factory=GlassOption)),
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
        if not 0 < sum(c * c for c in v) < math.inf:
            raise PydanticCustomError("up", "up {v} is not a nonzero vector of finite length, expected "
                                      "[x, y, z] such as [0, 0, 1]", {"v": list(v)})
        return v

