"""Planarity by the angle sum (paper section 2.2), at positions: :mod:`optimize.terms.facesum`.

``sum of corner angles - (k - 2) pi`` per face with 4 or more vertices
(radians, <= 0 up to rounding), residual ``(r,)`` and Jacobian ``(r, 3 n)`` at
``V (n, 3)``; the rows are the term's.
"""
from ...terms.facesum import at_positions as angle_sum

__all__ = ["angle_sum"]
