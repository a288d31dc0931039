"""Exact closest points for every solver: on triangle surfaces and on boundary curves.

- :class:`Reference` (``surface``): closest points and continuous normals on a
  triangulated reference, from k-d trees with an exactness bound;
- :class:`Footpoints` (``footpoints``): the same answers for query sets that
  move little per call (an optimizer's iterates), candidate triangles kept
  between calls, compiled kernels (:mod:`optimize.kernels`) when asked;
- :class:`BoundaryCurve` (``curve``): closest points and tangents on the
  boundary polylines of a mesh.
Names load on first use (PEP 562).
"""
from .._lazy import lazy_exports

_EXPORTS = {
    "Reference": ".surface", "closest_on_triangles": ".surface",
    "Footpoints": ".footpoints",
    "BoundaryCurve": ".curve", "closest_on_segments": ".curve",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
