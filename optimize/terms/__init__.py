"""The optimization problem: unknowns with named slices, and its terms, one module each.

- ``problem``: :class:`ProblemSpec`, the one description of a run (layout, normalization, fixed
  vertices, terms with their kind and weight, energies, tested defects); :func:`describe` decides,
  per target and method, which terms run;
- ``variables``: :class:`Layout`, the unknown vector's named blocks (vertices, normals, axes, ...);
- ``formulation``: :class:`Formulation`, the default method's rows of a description, evaluated;
- constraints, each ``terms(x, layout, ...) -> (r, J)``: the residual vector ``r (p,)`` (zero
  when the constraint holds) and its sparse Jacobian ``J (p, layout.size)`` at ``x``, at most
  quadratic in ``x``: ``planarity``, ``diagonals``, ``unit``, ``conical``, ``anglebalance``,
  ``anglesum``, ``facesum`` (the paper's angle sum), ``angles`` (their shared corner-angle
  rows), ``circular``, ``nodeaxes``, ``convexity``, ``edgefloor``, ``glide``, ``fixed``;
- energies: ``fairness`` (second differences along mesh polylines) and ``closeness``
  (tangent-plane distance to the reference, footpoints from :mod:`optimize.proximity`).
Both methods build on these, from one description: the default one (``solvers.guided``) calls
them; the paper's (``solvers.paper``) take the angle terms' corner sets (``rows``) and evaluate
them on fixed patterns, and the fairness, closeness and fixed terms as they are.
The solver, not the term, applies weights.  The modules load when imported
(``from optimize.terms import conical``).
"""
from .._lazy import lazy_exports

__all__ = ["anglebalance", "angles", "anglesum", "circular", "closeness", "conical", "convexity", "diagonals",
           "edgefloor", "facesum", "fairness", "fixed", "formulation", "glide", "nodeaxes", "planarity", "problem", "unit",
           "variables"]
__getattr__, __dir__ = lazy_exports(__name__, {}, globals())
