"""Single rows of quads (the target ``strip``): building them from two rails, and a trefoil band.

A strip with rails ``a_i`` and ``b_i`` has the quads ``(a_i, a_{i+1}, b_{i+1}, b_i)``
and the rulings ``a_i b_i``.  Closed strips join the last ruling to the first;
with a half twist (a Moebius band) ``a_{m-1}`` is joined to ``b_0``.  The
trefoil band is the paper's benchmark case (336 quads, Fig. 11 of Liu et al.
2006): a band along a trefoil knot whose rulings make half a turn about the
curve; it is not developable until optimized with target ``strip``.
"""
from __future__ import annotations

import numpy as np

from ..errors import MeshError
from ..mesh import Mesh


def strip_mesh(a: np.ndarray, b: np.ndarray, closed: str = "open", name: str = "strip") -> Mesh:
    """A strip between rails ``a (m, 3)`` and ``b (m, 3)``.

    closed : "open" (``m - 1`` quads) | "closed" (``m`` quads) | "twisted"
        (``m`` quads, the last one joining ``a_{m-1}`` to ``b_0`` and
        ``b_{m-1}`` to ``a_0``: a Moebius band).
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape or a.ndim != 2 or a.shape[1] != 3 or len(a) < 2:
        raise MeshError(f"{name}: rails have shapes {a.shape} and {b.shape}, expected two (m, 3), m >= 2")
    if closed not in ("open", "closed", "twisted"):
        raise MeshError(f"{name}: closed={closed!r}, expected 'open', 'closed' or 'twisted'")
    m = len(a)
    i = np.arange(m - 1)
    F = [np.stack([i, i + 1, m + i + 1, m + i], axis=1)]  # a_i = i, b_i = m + i
    if closed == "closed":
        F.append(np.array([[m - 1, 0, m, 2 * m - 1]]))
    elif closed == "twisted":
        F.append(np.array([[m - 1, m, 0, 2 * m - 1]]))
    return Mesh(np.concatenate([a, b]), np.concatenate(F), name=name)


def trefoil(t: np.ndarray) -> np.ndarray:
    """(k, 3) float: the trefoil knot ``(sin t + 2 sin 2t, cos t - 2 cos 2t, -sin 3t)``."""
    return np.stack([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)], axis=1)


def trefoil_band(n_quads: int = 336, width: float = 0.3, name: str = "trefoil_band") -> Mesh:
    """A Moebius band of ``n_quads`` quads along a trefoil knot (rulings of length ``width``).

    The rulings turn about the curve by half a turn relative to the Frenet
    frame, so the band closes with a half twist.  It is a smooth ruled surface
    but not a developable one: its quads are not planar.
    """
    t = np.linspace(0.0, 2 * np.pi, n_quads, endpoint=False)
    dt = 1e-4
    c = trefoil(t)
    d1 = (trefoil(t + dt) - trefoil(t - dt)) / (2 * dt)
    d2 = (trefoil(t + dt) - 2 * c + trefoil(t - dt)) / dt ** 2
    T = d1 / np.linalg.norm(d1, axis=1, keepdims=True)
    B = np.cross(d1, d2)
    B /= np.linalg.norm(B, axis=1, keepdims=True)
    N = np.cross(B, T)
    r = np.cos(t / 2)[:, None] * N + np.sin(t / 2)[:, None] * B
    half = 0.5 * width * r
    return strip_mesh(c - half, c + half, closed="twisted", name=name)
