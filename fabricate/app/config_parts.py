"""Config sections of the parts: dimensions, shop limits, stock sheets for the nested cut files, stock
bars for the cutting plan, the glazing gasket."""
from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, ValidationInfo, field_validator, model_serializer, model_validator
from pydantic_core import PydanticCustomError

from ..cad.glass import (BOUNDS, COATINGS, COLOUR_CHARS, EDGES, GAS_FILL_PCT, GASES, INTERLAYER_DENSITY, SEALS,
                         SPACERS, TREATMENTS, TYPES)
from ..cad.spec import BeamSpec, Limits, NodeSpec, PartSpec
from .config_section import Section, section_base, tuples

_Interlayer = Literal[tuple(INTERLAYER_DENSITY)]
_Treatment = Literal[tuple(TREATMENTS)]
_Edge = Literal[tuple(EDGES)]


def _mm(key: str):
    """A ``parts.glass`` key in mm: not given (null) takes the build-up's default; bounds those of
    :data:`fabricate.cad.glass.BOUNDS`."""
    return Field(default=None, **BOUNDS[key])


class PaneSection(Section):
    """One pane of an insulated unit: monolithic (``thickness_mm``) or laminated (``plies_mm`` and an
    interlayer between each two plies)."""

    type: Literal[TYPES[:2]] = "monolithic"
    thickness_mm: float | None = _mm("thickness_mm")
    plies_mm: tuple[float, ...] | None = None
    interlayer: _Interlayer | None = None
    interlayer_mm: float | None = _mm("interlayer_mm")
    treatment: _Treatment | list[_Treatment] | None = None
    edge_work: _Edge | list[_Edge] | None = None

    _plies = tuples("plies_mm")


class GlassSection(Section):
    """The glass build-up (see ``fabricate.cad.glass``): ``monolithic`` (``thickness_mm``),
    ``laminated`` (``plies_mm``, ``interlayer``, ``interlayer_mm``) or ``insulated`` (``outer`` and
    ``inner`` panes, ``cavity_mm`` of ``gas``, spacer ``edge_seal_mm``, stepped ``step_mm``)."""

    type: Literal[TYPES]
    thickness_mm: float | None = _mm("thickness_mm")
    plies_mm: tuple[float, ...] | None = None
    interlayer: _Interlayer | None = None
    interlayer_mm: float | None = _mm("interlayer_mm")
    outer: PaneSection | None = None
    inner: PaneSection | None = None
    cavity_mm: float | None = _mm("cavity_mm")
    gas: Literal[GASES] | None = None
    edge_seal_mm: float | None = _mm("edge_seal_mm")
    step_mm: float | None = _mm("step_mm")
    treatment: _Treatment | list[_Treatment] | None = None      # the glass order's vocabulary: fabricate.cad.glass
    edge_work: _Edge | list[_Edge] | None = None
    coatings: dict[int, Literal[COATINGS]] | None = None
    spacer: Literal[SPACERS] | None = None
    spacer_colour: str | None = Field(default=None, min_length=1, max_length=COLOUR_CHARS)
    secondary_seal: Literal[SEALS] | None = None
    gas_fill_pct: float | None = Field(default=None, **GAS_FILL_PCT)

    _plies = tuples("plies_mm")

    @model_validator(mode="after")
    def _consistent(self) -> "GlassSection":
        from optimize.errors import ConfigError

        from ..cad.glass import BuildUp

        try:
            BuildUp.from_config(self.model_dump())
        except ConfigError as exc:
            raise PydanticCustomError("glass_build_up", "{err}", {"err": str(exc)}) from None
        return self


MAX_SHEET_MM = 100_000.0
"""Longest side of a stock sheet (mm): 100 m; a jumbo glass sheet is 6 m, a steel plate 12-18 m."""

_SHEET_SIDE = dict(gt=0, le=MAX_SHEET_MM)
_Side = Annotated[float, Field(**_SHEET_SIDE)]


class LimitsSection(section_base(Limits, meta={"sheet_mm": {"items": _SHEET_SIDE}})):
    """What the shops can make; parts beyond it are flagged by id (defaults, bounds:
    :class:`fabricate.cad.spec.Limits`)."""


class BeamSection(section_base(BeamSpec)):
    """The beam section welded from plates, mm (defaults, bounds: :class:`fabricate.cad.spec.BeamSpec`)."""


class NodeSection(section_base(NodeSpec)):
    """How the beams meet at a node, mm (defaults, bounds: :class:`fabricate.cad.spec.NodeSpec`)."""


_NESTED = {
    "limits": (LimitsSection, Field(default_factory=LimitsSection)),
    "beam": (BeamSection, Field(default_factory=BeamSection)),
    "node": (NodeSection, Field(default_factory=NodeSection)),
    "glass": (GlassSection | None, Field(default=None)),
}


class PartsSection(section_base(PartSpec, extra=_NESTED)):
    """Part dimensions in mm and densities in kg/m3 (defaults, bounds, and the rules joining several
    keys: :class:`fabricate.cad.spec.PartSpec`)."""

    @model_validator(mode="after")
    def _one_build_up(self) -> "PartsSection":
        g = self.glass
        if g is not None and "glass_thickness" in self.model_fields_set and not (
                g.type == "monolithic" and g.thickness_mm == self.glass_thickness):
            raise PydanticCustomError(
                "glass_build_up", "parts.glass_thickness = {t} and parts.glass (type {kind}) are two build-ups; "
                "expected one of them (glass_thickness is the shorthand of a monolithic pane)",
                {"t": f"{self.glass_thickness:g}", "kind": g.type})
        return self

    @model_serializer(mode="wrap")
    def _dump(self, handler):
        """With a ``glass`` build-up, ``glass_thickness`` is left out of the dump (the config as run
        stays loadable: giving both is an error)."""
        data = handler(self)
        if self.glass is not None:
            data.pop("glass_thickness", None)
        return data


_MM = {"unit": "mm"}


class SheetSection(Section):
    """Stock sheets of one material for the nested cut files (mm)."""

    sheet_mm: tuple[_Side, _Side] = Field(json_schema_extra=_MM)
    margin_mm: float = Field(default=10.0, ge=0, le=1000.0, json_schema_extra=_MM)
    kerf_mm: float = Field(default=3.0, ge=0, le=100.0, json_schema_extra=_MM)
    rotation: bool = True

    _sheet_list = tuples("sheet_mm")


SHEETS = {"glass": {"sheet_mm": (6000.0, 3210.0), "margin_mm": 20.0, "kerf_mm": 10.0, "rotation": True},
          "steel": {"sheet_mm": (12000.0, 2500.0), "margin_mm": 10.0, "kerf_mm": 3.0, "rotation": True}}
"""The stock sheet of each material when the config does not say (README: outputs.nesting)."""


class NestingSection(Section):
    """Stock sheets per material: glass (jumbo 6000 x 3210, trimmed edges, room to grind between parts)
    and steel plate (12000 x 2500, plasma or laser kerf).  A material's section gives only the keys
    it changes: the others keep that material's defaults (:data:`SHEETS`)."""

    glass: SheetSection = Field(default_factory=lambda: SheetSection(**SHEETS["glass"]))
    steel: SheetSection = Field(default_factory=lambda: SheetSection(**SHEETS["steel"]))

    @field_validator("glass", "steel", mode="before")
    @classmethod
    def _defaults(cls, value, info: ValidationInfo):
        """The material's defaults under the keys given (a key's ``null``, or the section's: its default)."""
        if value is None:
            return dict(SHEETS[info.field_name])
        if isinstance(value, dict):
            return {**SHEETS[info.field_name], **{k: v for k, v in value.items() if v is not None}}
        return value


_Bar = Annotated[float, Field(gt=0, le=MAX_SHEET_MM)]


class BarsSection(Section):
    """Stock bars the beams and hub tubes are sawn from (mm; :mod:`fabricate.export.bars`: bar_order.csv,
    bar_cutting.csv, the cut list's ``bar``): the lengths a mill sells (EN 10219 / EN 10210 hollow
    sections: 6 and 12 m), the saw's kerf, what is squared off each mill end."""

    stock_lengths_mm: tuple[_Bar, ...] = Field(default=(6000.0, 12000.0), min_length=1, max_length=20,
                                               json_schema_extra=_MM)
    kerf_mm: float = Field(default=3.0, ge=0, le=50.0, json_schema_extra=_MM)
    end_trim_mm: float = Field(default=10.0, ge=0, le=1000.0, json_schema_extra=_MM)

    _lengths = tuples("stock_lengths_mm")

    @model_validator(mode="after")
    def _trims_fit(self) -> "BarsSection":
        if 2 * self.end_trim_mm >= max(self.stock_lengths_mm):
            raise PydanticCustomError("bars", "end_trim_mm = {t}: two trims must be shorter than the longest stock "
                                      "bar ({s} mm)", {"t": f"{self.end_trim_mm:g}",
                                                       "s": f"{max(self.stock_lengths_mm):g}"})
        return self


class GasketSection(Section):
    """The glazing gasket on a beam's flat top (:mod:`fabricate.export.gasket`: gasket.csv): the width the
    panel edge bears on (mm) and the fold between two panels (deg, 0 flat) beyond which a beam is
    a warning of the run."""

    bite_mm: float = Field(default=20.0, gt=0, le=500.0, json_schema_extra=_MM)
    max_fold_deg: float = Field(default=2.0, ge=0, le=90.0, json_schema_extra={"unit": "deg"})
