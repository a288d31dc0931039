"""Part dimensions: what the glass supplier and the steel shop are told (mm, kg/m3)."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

from optimize.errors import ConfigError

from .glass import BuildUp

EDGE_OPTIONS = ("auto", "axis", "perpendicular")


@dataclass(frozen=True)
class Limits:
    """What the shops can make (mm, degrees, kg); parts beyond them are flagged by id.

    min_corner_deg : smallest panel corner a glass supplier cuts without a special order.
    min_edge_mm : shortest panel or beam outline edge.
    sheet_mm : the largest glass sheet (jumbo / PLF 6000 x 3210): a panel's stock rectangle must fit.
    max_panel_kg : heaviest panel the site can lift into place.
    """

    min_corner_deg: float = 30.0
    min_edge_mm: float = 50.0
    sheet_mm: tuple[float, float] = (6000.0, 3210.0)
    max_panel_kg: float = 250.0

    def __post_init__(self) -> None:
        for key in ("min_corner_deg", "min_edge_mm", "max_panel_kg"):
            value = getattr(self, key)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ConfigError(f"parts.limits.{key} = {value!r}: expected a number >= 0")
        sheet = tuple(self.sheet_mm)
        if len(sheet) != 2 or not all(isinstance(v, (int, float)) and v > 0 for v in sheet):
            raise ConfigError(f"parts.limits.sheet_mm = {self.sheet_mm!r}: expected [width, height] > 0 (mm)")
        object.__setattr__(self, "sheet_mm", (float(max(sheet)), float(min(sheet))))


@dataclass(frozen=True)
class PartSpec:
    """Dimensions of panels, beams and nodes (mm) and densities (kg/m3).

    glass_thickness : monolithic panel thickness, measured along the face normal (the shorthand of
        ``glass = {type: monolithic, thickness_mm: t}``).  With ``glass`` given it is derived: the
        weight-equivalent glass thickness of the unit (:meth:`BuildUp.weight_thickness_mm`), which the
        structure's glass load uses.
    glass : None (monolithic ``glass_thickness``), a ``parts.glass`` mapping or a
        :class:`fabricate.cad.glass.BuildUp`; after construction always the BuildUp.
    joint_gap : gap between neighbouring panels; every panel edge is set back
        by half of it from the beam plane (``axis``) or the face edge
        (``perpendicular``).
    edge : panel side faces: ``axis`` lie in planes parallel to the beam planes
        (neighbouring panels then have parallel sides and cannot clash; exact
        for conical meshes), ``perpendicular`` are normal to the panel,
        ``auto`` picks ``axis`` for conical structures and ``perpendicular``
        otherwise.
    beam_width : beam thickness across its plane (the glass bears on
        ``(beam_width - joint_gap) / 2`` on each side).
    beam_depth : layer distance the pipeline uses for the default layers; the
        beams themselves run between the first and last layer of the
        structure (the BOM reports their real depth).
    node_radius : 0 for no nodes; otherwise a prism of this radius on every
        node axis, and the beams stop short of it.
    node_sides : number of sides of the node prism (a polygonal cylinder, so
        that STEP, STL and the analytic volume describe the same solid).
    steel_grade : written on the steel cut list (EN 10025 grade, e.g. S355).
    limits : :class:`Limits` the parts are held to (flagged in the report).
    """

    glass_thickness: float = 10.0
    joint_gap: float = 10.0
    edge: str = "auto"
    beam_width: float = 60.0
    beam_depth: float = 200.0
    node_radius: float = 0.0
    density_glass: float = 2500.0
    density_steel: float = 7850.0
    node_sides: int = 24
    steel_grade: str = "S355"
    limits: Limits = Limits()
    glass: Any = None

    def __post_init__(self) -> None:
        if isinstance(self.limits, dict):
            object.__setattr__(self, "limits", Limits(**self.limits))
        positive = ("glass_thickness", "beam_width", "beam_depth", "density_glass", "density_steel")
        for key in positive:
            value = getattr(self, key)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ConfigError(f"parts.{key} = {value!r}: expected a positive number (mm or kg/m3)")
        for key in ("joint_gap", "node_radius"):
            value = getattr(self, key)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ConfigError(f"parts.{key} = {value!r}: expected a number >= 0 (mm)")
        if self.edge not in EDGE_OPTIONS:
            raise ConfigError(f"parts.edge = {self.edge!r}: expected one of {', '.join(EDGE_OPTIONS)}")
        if self.joint_gap >= self.beam_width:
            raise ConfigError(f"parts.joint_gap = {self.joint_gap:g} mm is not below parts.beam_width = "
                              f"{self.beam_width:g} mm: the panels would not bear on the beams")
        if not (isinstance(self.node_sides, int) and self.node_sides >= 6):
            raise ConfigError(f"parts.node_sides = {self.node_sides!r}: expected an integer >= 6")
        if isinstance(self.glass, dict) and all(v is None for v in self.glass.values()):
            object.__setattr__(self, "glass", None)     # an empty section: the monolithic shorthand
        given = self.glass is not None
        build_up = BuildUp.from_config(self.glass, self.glass_thickness)
        object.__setattr__(self, "glass", build_up)
        if given:
            object.__setattr__(self, "glass_thickness", build_up.weight_thickness_mm(float(self.density_glass)))
        self.glass.check_bearing(0.5 * (self.beam_width - self.joint_gap))

    def edge_mode(self, is_conical: bool) -> str:
        """``axis`` or ``perpendicular``: ``auto`` resolved for a structure."""
        if self.edge == "auto":
            return "axis" if is_conical else "perpendicular"
        return self.edge

    def density(self, kind: str, material: str = "") -> float:
        """kg/m3 of a part kind (``panel`` glass, ``beam`` and ``node`` steel), or of a panel layer's
        ``material`` (``PartGroup.material``: an interlayer, see :mod:`fabricate.cad.glass`)."""
        if kind == "panel":
            return self.glass.density(material, self.density_glass) if material else self.density_glass
        return self.density_steel

    def group_density(self, group) -> float:
        """kg/m3 of the solids of a :class:`PartGroup`."""
        return self.density(group.kind, getattr(group, "material", ""))

    def as_dict(self) -> dict:
        return asdict(self)
