"""Remeshing: from a triangle surface (or far-from-PQ quads) to quads along principal directions.

- ``principal``, ``principal_quadric``: principal directions and curvatures;
- ``crossfield``: a smooth cross field; ``seamless``, ``isolines``, ``tracing``,
  ``boundary_cells``: parametrization and extraction of the cells;
- ``quads``: the chain (:func:`remesh`, :func:`surface_to_mesh`);
- ``routes``: a quad input's own lines against the remeshed route (:func:`optimize_routes`);
- ``surfaces``: test surfaces with known principal directions.
Names load on first use (PEP 562).
"""
from .._lazy import lazy_exports

_EXPORTS = {"remesh": ".quads", "surface_to_mesh": ".quads", "optimize_routes": ".routes"}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
