"""Config sections of the parts: dimensions, shop limits, stock sheets for the nested cut files."""
from __future__ import annotations

from typing import Literal

from pydantic import Field, field_validator, model_serializer, model_validator
from pydantic_core import PydanticCustomError

from .config_section import MAX_MM, Section

_tuple = field_validator("plies_mm", mode="before")(lambda v: tuple(v) if isinstance(v, list) else v)


class PaneSection(Section):
    """One pane of an insulated unit: monolithic (``thickness_mm``) or laminated (``plies_mm`` and an
    interlayer between each two plies)."""

    type: Literal["monolithic", "laminated"] = "monolithic"
    thickness_mm: float | None = Field(default=None, ge=2.0, le=25.0)
    plies_mm: tuple[float, ...] | None = None
    interlayer: Literal["PVB", "SGP"] | None = None
    interlayer_mm: float | None = Field(default=None, gt=0, le=10.0)

    _plies = _tuple


class GlassSection(Section):
    """The glass build-up (see ``fabricate.cad.glass``): ``monolithic`` (``thickness_mm``),
    ``laminated`` (``plies_mm``, ``interlayer``, ``interlayer_mm``) or ``insulated`` (``outer`` and
    ``inner`` panes, ``cavity_mm`` of ``gas``, spacer ``edge_seal_mm``, stepped ``step_mm``)."""

    type: Literal["monolithic", "laminated", "insulated"]
    thickness_mm: float | None = Field(default=None, ge=2.0, le=25.0)
    plies_mm: tuple[float, ...] | None = None
    interlayer: Literal["PVB", "SGP"] | None = None
    interlayer_mm: float | None = Field(default=None, gt=0, le=10.0)
    outer: PaneSection | None = None
    inner: PaneSection | None = None
    cavity_mm: float | None = Field(default=None, ge=4.0, le=50.0)
    gas: Literal["argon", "air", "krypton"] | None = None
    edge_seal_mm: float | None = Field(default=None, ge=5.0, le=50.0)
    step_mm: float | None = Field(default=None, ge=0.0, le=200.0)

    _plies = _tuple

    @model_validator(mode="after")
    def _consistent(self) -> "GlassSection":
        from optimize.errors import ConfigError

        from fabricate.cad.glass import BuildUp

        try:
            BuildUp.from_config(self.model_dump())
        except ConfigError as exc:
            raise PydanticCustomError("glass_build_up", "{err}", {"err": str(exc)}) from None
        return self


class LimitsSection(Section):
    """What the shops can make; parts beyond it are flagged by id (see ``fabricate.cad.spec.Limits``)."""

    min_corner_deg: float = Field(default=30.0, ge=0, lt=180)
    min_edge_mm: float = Field(default=50.0, ge=0, le=10000.0)
    sheet_mm: tuple[float, float] = (6000.0, 3210.0)
    max_panel_kg: float = Field(default=250.0, gt=0, le=100000.0)

    _sheet_list = field_validator("sheet_mm", mode="before")(lambda v: tuple(v) if isinstance(v, list) else v)


class BeamSection(Section):
    """The beam section welded from plates (see ``fabricate.cad.spec.BeamSpec``), mm."""

    section: Literal["plate", "rhs", "tee", "i"] = "plate"
    web_mm: float | None = Field(default=None, gt=0, le=2000.0)
    flange_mm: float = Field(default=12.0, gt=0, le=500.0)
    flange_width_mm: float = Field(default=200.0, gt=0, le=5000.0)


class NodeSection(Section):
    """How the beams meet at a node (see ``fabricate.cad.spec.NodeSpec``), mm."""

    connection: Literal["hub", "mitre", "none"] | None = None
    hub: Literal["tube", "solid"] = "tube"
    radius_mm: float | None = Field(default=None, gt=0, le=5000.0)
    wall_mm: float = Field(default=10.0, gt=0, le=1000.0)
    cap_mm: float = Field(default=15.0, gt=0, le=1000.0)
    gap_mm: float = Field(default=20.0, ge=0, le=5000.0)


class PartsSection(Section):
    """Part dimensions in mm and densities in kg/m3 (see ``fabricate.cad.PartSpec``)."""

    glass_thickness: float = Field(default=10.0, gt=0, le=200.0)
    joint_gap: float = Field(default=10.0, ge=0, le=1000.0)
    edge: Literal["auto", "axis", "perpendicular"] = "auto"
    beam_width: float = Field(default=60.0, gt=0, le=2000.0)
    beam_depth: float = Field(default=200.0, gt=0, le=MAX_MM)
    node_radius: float = Field(default=0.0, ge=0, le=5000.0)
    density_glass: float = Field(default=2500.0, gt=0, le=25000.0)
    density_steel: float = Field(default=7850.0, gt=0, le=25000.0)
    node_sides: int = Field(default=24, ge=6, le=256)
    steel_grade: str = Field(default="S355", min_length=1, max_length=40)
    limits: LimitsSection = Field(default_factory=LimitsSection)
    beam: BeamSection = Field(default_factory=BeamSection)
    node: NodeSection = Field(default_factory=NodeSection)
    glass: GlassSection | None = None

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


class SheetSection(Section):
    """Stock sheets of one material for the nested cut files (mm)."""

    sheet_mm: tuple[float, float]
    margin_mm: float = Field(default=10.0, ge=0, le=1000.0)
    kerf_mm: float = Field(default=3.0, ge=0, le=100.0)
    rotation: bool = True

    _sheet_list = field_validator("sheet_mm", mode="before")(lambda v: tuple(v) if isinstance(v, list) else v)


class NestingSection(Section):
    """Stock sheets per material: glass (jumbo 6000 x 3210, trimmed edges, room to grind between parts)
    and steel plate (12000 x 2500, plasma or laser kerf)."""

    glass: SheetSection = Field(default_factory=lambda: SheetSection(sheet_mm=(6000.0, 3210.0), margin_mm=20.0,
                                                                     kerf_mm=10.0))
    steel: SheetSection = Field(default_factory=lambda: SheetSection(sheet_mm=(12000.0, 2500.0), margin_mm=10.0,
                                                                     kerf_mm=3.0))
