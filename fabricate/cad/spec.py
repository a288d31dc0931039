"""Part dimensions: what the glass supplier and the steel shop are told (mm, kg/m3)."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

from optimize.errors import ConfigError

from .glass import BuildUp

EDGE_OPTIONS = ("auto", "axis", "perpendicular")
SECTIONS = ("plate", "rhs", "tee", "i")
CONNECTIONS = ("hub", "mitre", "none")
HUBS = ("tube", "solid")


def _number(key: str, value, low: float = 0.0, strict: bool = True) -> None:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or (value <= low if strict else value < low):
        raise ConfigError(f"{key} = {value!r}: expected a number {'>' if strict else '>='} {low:g} (mm)")


@dataclass(frozen=True)
class BeamSpec:
    """The beam section, welded from flat plates (mm); see :mod:`fabricate.cad.sections`.

    section : ``plate`` (one plate ``beam_width`` thick, today's beam), ``tee`` (web and a top
        flange on the glass side), ``i`` (web, top and bottom flange), ``rhs`` (two webs parallel
        to the beam plane, symmetric about it, top and bottom flange: a welded box).
    web_mm : web plate thickness (each of the two webs of an ``rhs``); None: ``beam_width``.
    flange_mm : flange plate thickness.
    flange_width_mm : overall width across the beam plane (the flanges; an ``rhs``'s outside width).
    The depth is the layer span (``beam_depth`` / ``offset.distances``): the beam fills it.
    """

    section: str = "plate"
    web_mm: float | None = None
    flange_mm: float = 12.0
    flange_width_mm: float = 200.0

    def __post_init__(self) -> None:
        if self.section not in SECTIONS:
            raise ConfigError(f"parts.beam.section = {self.section!r}: expected one of {', '.join(SECTIONS)}")
        if self.web_mm is not None:
            _number("parts.beam.web_mm", self.web_mm)
        _number("parts.beam.flange_mm", self.flange_mm)
        _number("parts.beam.flange_width_mm", self.flange_width_mm)


@dataclass(frozen=True)
class NodeSpec:
    """How beams meet at a node (mm); see :mod:`fabricate.cad.hubs`.

    connection : ``mitre`` (ends in the bisector planes through the node axis, no node part),
        ``hub`` (a hub on the node axis between the layers; the beams stop at it with square
        ends), ``none`` (square ends ``gap_mm`` short of the axis, no node part: the shop
        connects them), or None: ``hub`` when ``parts.node_radius`` > 0, else ``mitre``.
    hub : ``tube`` (a steel tube with a top and a bottom cap plate, three parts) or ``solid``
        (a solid polygonal hub, one part).
    radius_mm : hub outside radius (circumradius of its ``sides``-gon); None: ``node_radius``.
    wall_mm : tube wall; cap_mm : cap plate thickness; gap_mm : ``none``: end distance from the axis.
    """

    connection: str | None = None
    hub: str = "tube"
    radius_mm: float | None = None
    wall_mm: float = 10.0
    cap_mm: float = 15.0
    gap_mm: float = 20.0

    def __post_init__(self) -> None:
        if self.connection is not None and self.connection not in CONNECTIONS:
            raise ConfigError(f"parts.node.connection = {self.connection!r}: expected one of "
                              f"{', '.join(CONNECTIONS)}")
        if self.hub not in HUBS:
            raise ConfigError(f"parts.node.hub = {self.hub!r}: expected one of {', '.join(HUBS)}")
        if self.radius_mm is not None:
            _number("parts.node.radius_mm", self.radius_mm)
        _number("parts.node.wall_mm", self.wall_mm)
        _number("parts.node.cap_mm", self.cap_mm)
        _number("parts.node.gap_mm", self.gap_mm, strict=False)


@dataclass(frozen=True)
class Limits:
    """What the shops can make (mm, degrees, kg); parts beyond them are flagged by id.

    min_corner_deg : smallest panel corner a glass supplier cuts without a special order.
    min_edge_mm : shortest panel or beam outline edge (of a flange plate: its edges along the beam).
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
    beam : :class:`BeamSpec` (the section); node : :class:`NodeSpec` (the connection).
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
    beam: BeamSpec = BeamSpec()
    node: NodeSpec = NodeSpec()
    glass: Any = None

    def __post_init__(self) -> None:
        for key, cls in (("limits", Limits), ("beam", BeamSpec), ("node", NodeSpec)):
            if isinstance(getattr(self, key), dict):
                object.__setattr__(self, key, cls(**getattr(self, key)))
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
        if self.joint_gap >= self.bearing_width:
            key = "parts.beam_width" if self.beam.section == "plate" else "parts.beam.flange_width_mm"
            raise ConfigError(f"parts.joint_gap = {self.joint_gap:g} mm is not below {key} = "
                              f"{self.bearing_width:g} mm: the panels would not bear on the beams")
        b = self.beam
        if b.section in ("tee", "i") and b.flange_width_mm <= self.web:
            raise ConfigError(f"parts.beam.flange_width_mm = {b.flange_width_mm:g} mm: expected more than the web "
                              f"({self.web:g} mm) for a {b.section} section")
        if b.section == "rhs" and b.flange_width_mm <= 2 * self.web:
            raise ConfigError(f"parts.beam.flange_width_mm = {b.flange_width_mm:g} mm: expected more than two "
                              f"webs ({2 * self.web:g} mm) for an rhs section")
        if self.connection == "hub" and self.hub_radius <= 0:
            raise ConfigError("parts.node.connection = 'hub': expected parts.node.radius_mm (or "
                              "parts.node_radius) > 0 (mm)")
        if self.connection == "hub" and self.node.hub == "tube" and self.node.wall_mm >= self.hub_radius:
            raise ConfigError(f"parts.node.wall_mm = {self.node.wall_mm:g} mm: expected less than the hub "
                              f"radius {self.hub_radius:g} mm")
        if not (isinstance(self.node_sides, int) and self.node_sides >= 6):
            raise ConfigError(f"parts.node_sides = {self.node_sides!r}: expected an integer >= 6")
        if isinstance(self.glass, dict) and all(v is None for v in self.glass.values()):
            object.__setattr__(self, "glass", None)     # an empty section: the monolithic shorthand
        given = self.glass is not None
        build_up = BuildUp.from_config(self.glass, self.glass_thickness)
        object.__setattr__(self, "glass", build_up)
        if given:
            object.__setattr__(self, "glass_thickness", build_up.weight_thickness_mm(float(self.density_glass)))
        self.glass.check_bearing(0.5 * (self.bearing_width - self.joint_gap))

    @property
    def web(self) -> float:
        """Web plate thickness (mm): ``beam.web_mm`` or ``beam_width``."""
        return float(self.beam.web_mm if self.beam.web_mm is not None else self.beam_width)

    @property
    def bearing_width(self) -> float:
        """Width across the beam plane the glass bears on (mm): the plate or the flanges."""
        return self.beam_width if self.beam.section == "plate" else float(self.beam.flange_width_mm)

    @property
    def connection(self) -> str:
        """``hub`` | ``mitre`` | ``none`` (``parts.node.connection``, None resolved from ``node_radius``)."""
        if self.node.connection is not None:
            return self.node.connection
        return "hub" if self.node_radius > 0 else "mitre"

    @property
    def hub_kind(self) -> str:
        """``tube`` | ``solid``: today's ``node_radius`` alone builds the solid polygonal hub."""
        return self.node.hub if self.node.connection == "hub" else "solid"

    @property
    def hub_radius(self) -> float:
        """Hub outside radius (mm), 0 without hubs."""
        if self.connection != "hub":
            return 0.0
        return float(self.node.radius_mm if self.node.radius_mm is not None else self.node_radius)

    @property
    def end_setback(self) -> float:
        """How far the square beam ends stand off the node axis at least (mm); 0: mitred ends."""
        return {"hub": self.hub_radius, "none": float(self.node.gap_mm), "mitre": 0.0}[self.connection]

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
