"""The paper's own methods (Liu et al. 2006, section 2.2): penalty, SQP, hybrid; strip target.

``optimize_mesh`` is the name ``optimize.api`` dispatches to; it is
:func:`run_paper_method`.  The per-method entry points live in the modules
``optimize.solvers.paper.penalty``, ``.sqp`` and ``.hybrid`` (functions of the same
names), not re-exported here so that the module names stay importable.  The
paper's constraints at positions are the terms' (``optimize.terms.facesum``,
``anglebalance``, ``anglesum``, ``determinants``: ``at_positions``).
Names load on first use (PEP 562).
"""
from ..._lazy import lazy_exports

_EXPORTS = {
    "METHODS": ".hybrid", "run_paper_method": ".hybrid", "optimize_mesh": ".hybrid:run_paper_method",
    "TARGETS": ".targets", "check_strip": ".targets", "target_terms": ".targets",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
