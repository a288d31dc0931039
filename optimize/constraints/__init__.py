"""Constraints of the optimizer, one module each.

Every module has ``terms(x, layout, ...) -> (r, J)``: the residual vector
``r (p,)`` (zero when the constraint holds) and its sparse Jacobian
``J (p, layout.size)`` at the unknown vector ``x``.  All residuals are at most
quadratic in ``x``.  The solver, not the constraint, applies weights.
The modules load when imported (``from optimize.constraints import conical``).
"""
from .._lazy import lazy_exports

__all__ = ["anglebalance", "angles", "anglesum", "circular", "closeness", "conical", "convexity", "diagonals", "edgefloor",
           "fixed", "glide", "nodeaxes", "planarity", "unit"]
__getattr__, __dir__ = lazy_exports(__name__, {}, globals())
