"""The mesh model: polygon meshes, their topology, measures, corner angles and files.

- ``core``: :class:`Mesh` (``V (n, 3)`` float, padded faces ``F (m, k)`` int, validated);
- ``topology``: :class:`Topology` (edges, corners, vertex stars, boundary loops; cached);
- ``measures``: planarity, conical and circular defects, normals, areas, folds (the shared definitions);
- ``corners``: corner angles and their gradients (the one kernel);
- ``axes``: node axes fitted to the face normals (the one fit: optimizer results, offset stage);
- ``components``: connected components;
- ``conjugacy``: how far a quad mesh's lines are from a conjugate net (a measure of the net);
- ``io``: OBJ, OFF, PLY, STL and 3dm readers and writers (:func:`read_mesh`, :func:`write_mesh`).
Names load on first use (PEP 562).
"""
from .._lazy import lazy_exports

_EXPORTS = {
    "Mesh": ".core", "pad_faces": ".core", "padding_limit": ".core", "unit_exponent": ".core",
    "area_ratio": ".core", "ZERO_AREA": ".core", "ZERO_EDGE": ".core",
    "Topology": ".topology",
    "read_mesh": ".io", "write_mesh": ".io",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
