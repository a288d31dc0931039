"""The paper's own methods (Liu et al. 2006, section 2.2): penalty, SQP, hybrid; strip target.

``optimize_mesh`` is the name ``optimize.api`` dispatches to; it is
:func:`run_paper_method`.  The per-method entry points live in the modules
``optimize.paper.penalty``, ``.sqp`` and ``.hybrid`` (functions of the same
names), not re-exported here so that the module names stay importable.
"""
from .angle_sum import angle_sum
from .angles import corner_angle_terms
from .balance import angle_balance
from .circular import circular_angles
from .det import det_constraints
from .hybrid import METHODS, run_paper_method
from .targets import TARGETS, check_strip, target_terms

optimize_mesh = run_paper_method

__all__ = ["METHODS", "TARGETS", "angle_balance", "angle_sum", "check_strip", "circular_angles",
           "corner_angle_terms", "det_constraints", "optimize_mesh", "run_paper_method", "target_terms"]
