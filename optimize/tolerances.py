"""The one tolerance object of the package.

All geometric checks (planarity, conical and circular defects, offsets, CAD
tolerances) read their thresholds from a :class:`Tolerances` instance, so that
a report can quote exactly what was tested.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, replace

CLOSEST_TIE = 1e-6
"""Squared distances to a reference within this (relative) of the least are a tie among closest points,
which the lowest triangle index wins in every search path (``optimize.proximity.surface``,
``Footpoints``, the compiled kernels), so mirror-image footpoints are not picked by rounding."""

HELD_TO = {"det": "planarity", "glide": "planarity", "short_edge": "planarity",
           "node_cone": "conical", "beam": "conical"}
"""Derived defects of the solvers and the tolerance each is held to: ``det`` (the paper's strip
determinants), ``glide`` (distance of gliding vertices to the boundary curve / mean edge),
``short_edge`` (how far an edge at a gliding vertex fell below its floor / mean edge),
``node_cone`` and ``beam`` (the node-axis rows of torsion-free beams, radians)."""


@dataclass(frozen=True)
class Tolerances:
    """Thresholds for every check.

    planarity : relative (diagonal distance / mean diagonal length for quads,
        max plane distance / mean edge length for n-gons).
    conical : radians, ``|w1 + w3 - w2 - w4|`` at interior valence-4 vertices.
    circular : radians, ``max(|phi1 + phi3 - pi|, |phi2 + phi4 - pi|)`` per quad.
    offset : relative to the offset distance, face-to-face distance error.
    beam_planarity : relative, planarity of the beam quads.
    cad_linear_mm : absolute, OpenCASCADE's modelling tolerance in mm.
    closeness : relative to the bounding-box diagonal, max distance to the
        reference surface (reported, not enforced by the optimizer).
    closeness_mm : absolute (mm), a limit on how far the design may move: when
        given, closeness becomes a requirement of the run (``None``: reported only).
    roughness : the result's roughness (mean second difference along the mesh
        lines over the mean edge) over the input's: above it, a warning.
    beam_twist_mm : absolute, the largest twist of a beam a steel shop takes.
    fold : signed corner sine: a corner convex in the input (sine above ``-fold``)
        that ends below ``-fold`` is dented (``measures.folded_faces``, the
        optimizer's fold check and convexity rows).
    strip_parallel : sine of the angle below which two rulings of a developable
        strip count as parallel (``modelling.strip_analysis``).
    file_volume : relative, the volume of every solid read back from a written
        file against the bill of materials (3MF, STL, STEP, IFC).
    file_area : relative, the area of every cut outline read back from the cut
        files against the flat data.
    file_edge_mm : absolute, the edge lengths of those outlines.
    """

    planarity: float = 1e-6
    conical: float = 1e-6
    circular: float = 1e-6
    offset: float = 1e-6
    beam_planarity: float = 1e-6
    cad_linear_mm: float = 1e-3
    closeness: float = 5e-3
    closeness_mm: float | None = None
    roughness: float = 2.0
    beam_twist_mm: float = 1.0
    fold: float = 1e-6
    strip_parallel: float = 1e-6
    file_volume: float = 1e-6
    file_area: float = 1e-9
    file_edge_mm: float = 1e-6

    def for_defect(self, name: str) -> float:
        """The threshold a solver's stop test holds the defect ``name`` to: a field of its own,
        or for the derived defects :data:`HELD_TO`'s field (``det``, ``glide``, ``short_edge``:
        planarity; ``node_cone``, ``beam``: conical).  Raises ValueError for an unknown name."""
        field_name = HELD_TO.get(name, name)
        if field_name not in self.__dataclass_fields__:
            raise ValueError(f"defect {name!r} has no tolerance, expected a field of Tolerances or one of "
                             f"{sorted(HELD_TO)}")
        return getattr(self, field_name)

    def replace(self, **changes: float) -> "Tolerances":
        """Return a copy with some thresholds changed."""
        return replace(self, **changes)

    def as_dict(self) -> dict[str, float]:
        return asdict(self)


DEFAULT = Tolerances()
