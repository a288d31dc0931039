"""Exporters: parts in, files out (STEP, STL, 3MF, DXF, SVG, bill of materials, IFC, .3dm); all atomic.

IFC and .3dm load their libraries (ifcopenshell, rhino3dm) only when called."""
from .bom import write_bom
from .cutfiles import write_cut_files, write_layout_plan
from .dxf import write_dxf
from .flatdata import write_flat
from .gltf import write_parts_gltf
from .nc1 import write_nc1
from .nesting import Layout, layout
from .schedules import write_glass_schedule, write_node_schedule, write_steel_cut_list
from .step import write_step
from .stl import write_stl, write_stl_parts
from .svg import write_svg
from .threemf import write_3mf


def write_ifc(parts, path, **kwargs) -> dict:
    """IFC4 of every part (:func:`fabricate.export.ifc.write_ifc`)."""
    from .ifc import write_ifc as write

    return write(parts, path, **kwargs)


def write_3dm(parts, path, **kwargs) -> dict:
    """Rhino .3dm of every part, the design mesh, layers and node axes (:func:`fabricate.export.rhino.write_3dm`)."""
    from .rhino import write_3dm as write

    return write(parts, path, **kwargs)


__all__ = ["Layout", "layout", "write_3dm", "write_3mf", "write_bom", "write_cut_files", "write_dxf", "write_flat",
           "write_glass_schedule", "write_ifc", "write_layout_plan", "write_nc1", "write_node_schedule",
           "write_parts_gltf", "write_steel_cut_list", "write_step", "write_stl", "write_stl_parts", "write_svg"]
