"""CAD stage: glass panels, beams and nodes as pure data (no CAD kernel needed to build them)."""
from .build import build_parts
from .parts import COLOURS, KINDS, Part, PartGroup, Parts, part_ids
from .spec import PartSpec

__all__ = ["COLOURS", "KINDS", "Part", "PartGroup", "PartSpec", "Parts", "build_parts", "part_ids"]
