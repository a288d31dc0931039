"""The solvers over the terms of ``optimize.terms``, all returning :class:`optimize.result.OptimizeResult`.

- ``guided``: the default method, regularized Gauss-Newton on the quadratic
  formulation (:func:`solve`), driven by :func:`optimize.api.run`;
- ``paper``: the paper's penalty, SQP and hybrid methods (:func:`run_paper_method`),
  imported only when one of them is asked for.
Settings and their defaults: :class:`optimize.options.OptimizeOptions`.
Names load on first use (PEP 562).
"""
from .._lazy import lazy_exports

_EXPORTS = {"solve": ".guided", "run_paper_method": ".paper"}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
