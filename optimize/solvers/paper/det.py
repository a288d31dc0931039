"""The strip determinants (paper, PQ strips): the term :mod:`optimize.terms.determinants`.

``det_constraints(mesh, V)`` is its residual ``(4 q,)`` and Jacobian ``(4 q, 3 n)``
at positions ``V (n, 3)``; ``det_local`` and ``det_combined_local`` its local kernels.
"""
from ...terms.determinants import at_positions as det_constraints
from ...terms.determinants import det_combined_local, det_local

__all__ = ["det_combined_local", "det_constraints", "det_local"]
