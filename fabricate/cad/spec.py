"""Part dimensions: what the glass supplier and the steel shop are told (mm, kg/m3).

The frozen dataclasses here are the one source of the defaults, bounds, units and help of the
``parts`` config section (``fabricate.app.config_parts`` derives it from them); constructing one
checks the choices and lower bounds of its fields (:func:`fabricate.fields.check_fields`) and the
rules that join several keys (the joint gap below the bearing width, flanges wider than the web,
the hub radius), each written here only.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any, Literal

from optimize.errors import ConfigError

from ..fields import MAX_MM, check_fields, option
from .glass import GLASS_THICKNESS, BuildUp


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

    section: Literal["plate", "rhs", "tee", "i"] = option("plate", help="plate, tee, i or rhs, welded from plates")
    web_mm: float | None = option(None, gt=0, le=2000.0, unit="mm", help="web plate thickness (null: beam_width)")
    flange_mm: float = option(12.0, gt=0, le=500.0, unit="mm", help="flange plate thickness")
    flange_width_mm: float = option(200.0, gt=0, le=5000.0, unit="mm", help="overall width across the beam plane")

    def __post_init__(self) -> None:
        check_fields(self, "parts.beam")


@dataclass(frozen=True)
class NodeSpec:
    """How beams meet at a node (mm); see :mod:`fabricate.cad.hubs`.

    connection : ``mitre`` (ends in the bisector planes through the node axis, no node part),
        ``hub`` (a hub on the node axis between the layers; the beams stop at it with square
        ends), ``none`` (square ends ``gap_mm`` short of the axis, no node part: the shop
        connects them), or None: ``hub`` when ``parts.node_radius`` > 0, else ``mitre``.
    hub : ``tube`` (a steel tube with a top and a bottom cap plate, three parts) or ``solid``
        (a solid polygonal hub, one part).
    radius_mm : hub outside radius (circumradius of its ``sides``-gon); None: ``node_radius``, and when
        that is 0 the smallest stock tube on which the beams of the sharpest node clear each other
        (sized by ``build_parts``, :mod:`fabricate.cad.hubsize`).
    wall_mm : tube wall; cap_mm : cap plate thickness; gap_mm : ``none``: end distance from the axis.
    """

    connection: Literal["hub", "mitre", "none"] | None = option(
        None, help="hub, mitre or none (null: hub when node_radius > 0)")
    hub: Literal["tube", "solid"] = option("tube", help="a tube with cap plates, or a solid polygonal hub")
    radius_mm: float | None = option(None, gt=0, le=5000.0, unit="mm",
                                     help="hub outside radius (null: node_radius; with node_radius 0, the smallest "
                                          "stock tube that clears the sharpest beam angle at every node)")
    wall_mm: float = option(10.0, gt=0, le=1000.0, unit="mm", help="tube wall")
    cap_mm: float = option(15.0, gt=0, le=1000.0, unit="mm", help="cap plate thickness")
    gap_mm: float = option(20.0, ge=0, le=5000.0, unit="mm", help="connection none: end distance from the axis")

    def __post_init__(self) -> None:
        check_fields(self, "parts.node")


@dataclass(frozen=True)
class Limits:
    """What the shops can make (mm, degrees, kg); parts beyond them are flagged by id.

    min_corner_deg : smallest panel corner a glass supplier cuts without a special order (hub cap
        plates are held to it too).
    min_edge_mm : shortest panel or beam outline edge (of a flange plate: its edges along the beam; of a
        hub cap plate: its width, its edges being the facets of a round plate).
    sheet_mm : the largest glass sheet (jumbo / PLF 6000 x 3210): a panel's stock rectangle must fit.
    max_panel_kg : heaviest panel the site can lift into place.
    """

    min_corner_deg: float = option(30.0, ge=0, lt=180, unit="deg", help="smallest panel corner")
    min_edge_mm: float = option(50.0, ge=0, le=10000.0, unit="mm", help="shortest panel or beam outline edge")
    sheet_mm: tuple[float, float] = option((6000.0, 3210.0), unit="mm", help="the largest glass sheet")
    max_panel_kg: float = option(250.0, gt=0, le=100000.0, unit="kg", help="heaviest panel the site can lift")

    def __post_init__(self) -> None:
        check_fields(self, "parts.limits")
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
    steel_grade : written on the steel cut list, the IFC and the NC1 files (EN 10025 grade with its quality,
        e.g. S355J2, the default).
    beam : :class:`BeamSpec` (the section); node : :class:`NodeSpec` (the connection).
    limits : :class:`Limits` the parts are held to (flagged in the report).
    """

    glass_thickness: float = option(10.0, **GLASS_THICKNESS, unit="mm", help="monolithic panel thickness")
    joint_gap: float = option(10.0, ge=0, le=1000.0, unit="mm", help="gap between neighbouring panels")
    edge: Literal["auto", "axis", "perpendicular"] = option("auto", help="panel sides: axis, perpendicular or auto")
    beam_width: float = option(60.0, gt=0, le=2000.0, unit="mm", help="beam thickness across its plane")
    beam_depth: float = option(200.0, gt=0, le=MAX_MM, unit="mm", help="layer distance of the default layers")
    node_radius: float = option(0.0, ge=0, le=5000.0, unit="mm", help="0: no nodes; else the hub radius")
    density_glass: float = option(2500.0, gt=0, le=25000.0, unit="kg/m3")
    density_steel: float = option(7850.0, gt=0, le=25000.0, unit="kg/m3")
    node_sides: int = option(24, ge=6, le=256, help="sides of the polygonal hub")
    steel_grade: str = option("S355J2", min_length=1, max_length=40,
                               help="EN 10025 grade with its quality (S355J2, S355J0, S275JR ...) on the cut list, IFC, NC1")
    limits: Limits = Limits()
    beam: BeamSpec = BeamSpec()
    node: NodeSpec = NodeSpec()
    glass: Any = None

    def __post_init__(self) -> None:
        for key, cls in (("limits", Limits), ("beam", BeamSpec), ("node", NodeSpec)):
            if isinstance(getattr(self, key), dict):
                object.__setattr__(self, key, cls(**getattr(self, key)))
        check_fields(self, "parts")
        if self.joint_gap >= self.bearing_width:
            key = "parts.beam_width" if self.beam.section == "plate" else "parts.beam.flange_width_mm"
            raise ConfigError(f"parts.joint_gap = {self.joint_gap:g} mm is not below {key} = "
                              f"{self.bearing_width:g} mm: expected a smaller gap so that the panels bear on the "
                              "beams")
        b = self.beam
        if b.section in ("tee", "i") and b.flange_width_mm <= self.web:
            raise ConfigError(f"parts.beam.flange_width_mm = {b.flange_width_mm:g} mm: expected more than the web "
                              f"({self.web:g} mm) for a {b.section} section")
        if b.section == "rhs" and b.flange_width_mm <= 2 * self.web:
            raise ConfigError(f"parts.beam.flange_width_mm = {b.flange_width_mm:g} mm: expected more than two "
                              f"webs ({2 * self.web:g} mm) for an rhs section")
        # a hub without a radius (radius_mm: null, node_radius: 0) is sized by build_parts from the sharpest
        # beam angle (fabricate.cad.hubsize); a radius given must leave room for the tube's wall
        if self.connection == "hub" and self.node.hub == "tube" and self.hub_radius > 0 \
                and self.node.wall_mm >= self.hub_radius:
            raise ConfigError(f"parts.node.wall_mm = {self.node.wall_mm:g} mm: expected less than the hub "
                              f"radius {self.hub_radius:g} mm")
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
