"""Circular quads (paper eq. 7), at positions: :mod:`optimize.terms.anglesum`.

``phi1 + phi3 - pi`` and ``phi2 + phi4 - pi`` per quad (rows ``2 i``, ``2 i + 1``),
residual ``(2 q,)`` and Jacobian ``(2 q, 3 n)`` at ``V (n, 3)``; the rows are the term's.
"""
from ...terms.anglesum import at_positions as circular_angles

__all__ = ["circular_angles"]
