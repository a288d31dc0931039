"""Offset stage (paper section 4): constant-distance layers, node axes, torsion-free beams."""
from .axes import AXIS_RCOND, AxisFit, face_planes, fit_axes, given_axes
from .beams import beam_normals, beam_planarity, beam_quads, beam_twist
from .files import layer_filename, write_offset_files
from .focal import (FocalMeshes, axis_line_intersections, edge_families, focal_meshes,
                    quad_circular_defect, spherical_image, spherical_image_defect)
from .layers import face_distance_errors, face_offset_heights, offset_layers
from .report import offset_report
from .straighten import coplanarity_residual, straighten_free_axes
from .structure import OffsetStructure, offset_structure, require_pq

__all__ = [
    "AXIS_RCOND", "AxisFit", "FocalMeshes", "OffsetStructure", "axis_line_intersections",
    "beam_normals", "beam_planarity", "beam_quads", "beam_twist", "coplanarity_residual",
    "edge_families", "face_distance_errors", "face_offset_heights", "face_planes", "fit_axes",
    "focal_meshes", "given_axes", "layer_filename", "offset_layers", "offset_report", "offset_structure",
    "quad_circular_defect", "require_pq", "spherical_image", "spherical_image_defect",
    "straighten_free_axes", "write_offset_files",
]
