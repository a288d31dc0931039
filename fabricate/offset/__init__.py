"""Offset stage (paper section 4): constant-distance layers, node axes, torsion-free beams.

Names load on first use (PEP 562), so importing one stage does not load the others.
"""
from optimize._lazy import lazy_exports

_EXPORTS = {
    "AXIS_RCOND": ".axes", "AxisFit": ".axes", "face_planes": ".axes", "fit_axes": ".axes",
    "given_axes": ".axes",
    "beam_normals": ".beams", "beam_planarity": ".beams", "beam_quads": ".beams", "beam_twist": ".beams",
    "layer_filename": ".files", "write_offset_files": ".files",
    "FocalMeshes": ".focal", "axis_line_intersections": ".focal", "edge_families": ".focal",
    "focal_meshes": ".focal", "quad_circular_defect": ".focal", "spherical_image": ".focal",
    "spherical_image_defect": ".focal",
    "face_distance_errors": ".layers", "face_offset_heights": ".layers", "offset_layers": ".layers",
    "offset_report": ".report",
    "coplanarity_residual": ".straighten", "straighten_free_axes": ".straighten",
    "OffsetStructure": ".structure", "offset_structure": ".structure", "require_pq": ".structure",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
