"""Part dimensions: what the glass supplier and the steel shop are told (mm, kg/m3)."""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from optimize.errors import ConfigError

EDGE_OPTIONS = ("auto", "axis", "perpendicular")


@dataclass(frozen=True)
class PartSpec:
    """Dimensions of panels, beams and nodes (mm) and densities (kg/m3).

    glass_thickness : panel thickness, measured along the face normal.
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

    def __post_init__(self) -> None:
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

    def edge_mode(self, is_conical: bool) -> str:
        """``axis`` or ``perpendicular``: ``auto`` resolved for a structure."""
        if self.edge == "auto":
            return "axis" if is_conical else "perpendicular"
        return self.edge

    def density(self, kind: str) -> float:
        """kg/m3 of a part kind (``panel`` glass, ``beam`` and ``node`` steel)."""
        return self.density_glass if kind == "panel" else self.density_steel

    def as_dict(self) -> dict:
        return asdict(self)
