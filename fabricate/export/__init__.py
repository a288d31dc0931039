"""Exporters: parts in, files out (STEP, STL, 3MF, DXF, SVG, bill of materials, IFC, .3dm); all atomic.

IFC and .3dm load their libraries (ifcopenshell, rhino3dm) only when called."""
from .bom import write_bom
from .dxf import write_dxf
from .gltf import write_parts_gltf
from .nc1 import write_nc1
from .nesting import Layout, layout
from .step import write_step
from .stl import write_stl
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


__all__ = ["write_ifc", "write_3dm", "write_nc1", "write_parts_gltf", "Layout", "layout", "write_3mf", "write_bom", "write_dxf", "write_step", "write_stl", "write_svg"]
