"""Conical angle balance (paper eq. 6), at positions: :mod:`optimize.terms.anglebalance`.

``w1 - w2 + w3 - w4`` per ``topology.interior_valence4`` vertex (radians),
residual ``(p,)`` and Jacobian ``(p, 3 n)`` at ``V (n, 3)``; the rows are the term's.
"""
from ...terms.anglebalance import at_positions as angle_balance

__all__ = ["angle_balance"]
