"""Modelling: built-in shapes and designs, subdivision, strips, and the subdivide-and-perturb loop.

- ``shapes``: grids, surfaces of revolution, translational surfaces, noise;
- ``designs``: the built-in designs (:data:`DESIGNS`: railway station, trefoil band, ...);
  ``design_tunnel``: the tunnel design;
- ``subdivision`` (Catmull-Clark, Doo-Sabin as sparse operators ``S``), ``curves``
  (Chaikin, Lane-Riesenfeld);
- ``strips`` and ``strip_analysis``: developable strips, their rulings, unrolling and singular curve;
- ``hierarchy``: :func:`subdivide_and_perturb`, "subdivide once, perturb, repeat".
Names load on first use (PEP 562).
"""
from .._lazy import lazy_exports

_EXPORTS = {"DESIGNS": ".designs", "subdivide_and_perturb": ".hierarchy", "strip_mesh": ".strips"}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
