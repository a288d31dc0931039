"""Exporters: parts in, files out (STEP, STL, 3MF, DXF, SVG, bill of materials); all atomic.

Names load on first use (PEP 562), so importing one stage does not load the others.
"""
from optimize._lazy import lazy_exports

_EXPORTS = {
    "write_bom": ".bom",
    "write_dxf": ".dxf",
    "Layout": ".nesting", "layout": ".nesting",
    "write_step": ".step",
    "write_stl": ".stl",
    "write_svg": ".svg",
    "write_3mf": ".threemf",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
