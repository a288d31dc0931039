"""CAD stage: glass panels, beams and nodes as pure data (no CAD kernel needed to build them).

Names load on first use (PEP 562), so importing one stage does not load the others.
"""
from optimize._lazy import lazy_exports

_EXPORTS = {
    "build_parts": ".build",
    "COLOURS": ".parts", "KINDS": ".parts", "Part": ".parts", "PartGroup": ".parts", "Parts": ".parts",
    "part_ids": ".parts",
    "PartSpec": ".spec",
    "PartError": ".errors",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
