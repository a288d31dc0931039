"""Exporters: parts in, files out (STEP, STL, 3MF, DXF, SVG, bill of materials); all atomic."""
from .bom import write_bom
from .cutfiles import write_cut_files, write_layout_plan
from .dxf import write_dxf
from .flatdata import write_flat
from .nesting import Layout, layout
from .schedules import write_glass_schedule, write_node_schedule, write_steel_cut_list
from .step import write_step
from .stl import write_stl, write_stl_parts
from .svg import write_svg
from .threemf import write_3mf

__all__ = ["Layout", "layout", "write_3mf", "write_bom", "write_cut_files", "write_dxf", "write_flat",
           "write_glass_schedule", "write_layout_plan", "write_node_schedule", "write_steel_cut_list", "write_step",
           "write_stl", "write_stl_parts", "write_svg"]
