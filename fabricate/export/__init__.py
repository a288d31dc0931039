"""Exporters: parts in, files out (STEP, STL, 3MF, DXF, SVG, bill of materials, IFC, .3dm); all atomic.

Names load on first use (PEP 562), so importing one exporter does not load the others;
IFC and .3dm load their libraries (ifcopenshell, rhino3dm) only when called.
"""
from optimize._lazy import lazy_exports

_EXPORTS = {
    "write_bom": ".bom",
    "write_cut_files": ".cutfiles", "write_layout_plan": ".cutfiles", "nest_cut_files": ".cutfiles",
    "write_dxf": ".dxf",
    "write_flat": ".flatdata",
    "write_glass_order": ".glass_order",
    "write_glass_schedule": ".schedules", "write_node_schedule": ".schedules",
    "write_steel_cut_list": ".schedules",
    "write_parts_gltf": ".gltf",
    "write_nc1": ".nc1",
    "Layout": ".nesting", "layout": ".nesting",
    "write_step": ".step",
    "write_stl": ".stl", "write_stl_parts": ".stl",
    "write_svg": ".svg",
    "write_3mf": ".threemf",
    "write_weld_schedule": ".welds",
    "write_bar_order": ".bars", "write_bar_cutting": ".bars",
    "write_gasket_schedule": ".gasket",
}

def write_ifc(parts, path, **kwargs) -> dict:
    """IFC4 of every part (:func:`fabricate.export.ifc.write_ifc`)."""
    from .ifc import write_ifc as write

    return write(parts, path, **kwargs)


def write_3dm(parts, path, **kwargs) -> dict:
    """Rhino .3dm of every part, the design mesh, layers and node axes (:func:`fabricate.export.rhino.write_3dm`)."""
    from .rhino import write_3dm as write

    return write(parts, path, **kwargs)


__all__ = sorted([*_EXPORTS, "write_ifc", "write_3dm"])
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
