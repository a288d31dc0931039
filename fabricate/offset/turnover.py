"""Offset faces that turn over: an offset beyond the focal distance.

A layer at distance ``d`` has the corners ``p_j + d x_j`` (``x_j`` the offset
vectors ``a_v / cos(theta_v)``).  The vector area of an offset face, along its
original unit normal ``n``, is a quadratic in ``d``::

    q(d) = n . A(d) = a + b d + c d^2,
    a = n . 1/2 sum p_j x p_(j+1),
    b = n . 1/2 sum (p_j x x_(j+1) + x_j x p_(j+1)),
    c = n . 1/2 sum x_j x x_(j+1)

(Newell's formula).  The face collapses where ``q`` reaches 0 (its roots are the face's focal
distances); past a root it is turned over (its normal flips) or, past a
double root, point-reflected through a focal point: either way the panel
and the beams around it cross.  Past the nearest root on either side the offset layer is no
longer a mesh anyone can build; the report names those faces and the safe
range of distances.
"""
from __future__ import annotations

import numpy as np

from optimize.mesh import Mesh

NAMED = 10
"""How many face ids a report names per layer."""


def _closed(F: np.ndarray) -> np.ndarray:
    """(m, k) corners with padding slots replaced by the face's first corner (area unchanged)."""
    return np.where(F >= 0, F, F[:, :1])


def area_quadratic(mesh: Mesh, normals: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """(m, 3) coefficients ``(a, b, c)`` of ``q(d)`` for every face.

    normals : (m, 3) unit face normals (the offset side); offset : (n, 3) offset vectors.
    """
    C = _closed(mesh.F)
    P, X = mesh.V[C], offset[C]                       # (m, k, 3)
    P1, X1 = np.roll(P, -1, axis=1), np.roll(X, -1, axis=1)
    A0 = 0.5 * np.cross(P, P1).sum(axis=1)
    A1 = 0.5 * (np.cross(P, X1) + np.cross(X, P1)).sum(axis=1)
    A2 = 0.5 * np.cross(X, X1).sum(axis=1)
    return np.stack([np.einsum("mj,mj->m", A, normals) for A in (A0, A1, A2)], axis=1)


COLLAPSE = 1e-6
"""A face whose offset area falls to this share of its own has collapsed: past it the face is turned
over or point-reflected (through a focal point, as a sphere's faces at its centre)."""


def turned_faces(coef: np.ndarray, d: float) -> np.ndarray:
    """Indices of the faces whose offset turned over or collapsed somewhere between 0 and ``d``:
    ``q(t) / q(0) <= COLLAPSE`` for a ``t`` in ``[0, d]`` (``coef (m, 3)`` of :func:`area_quadratic`)."""
    a, b, c = coef.T
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.stack([np.ones_like(a), 1 + (b + c * d) * d / a], axis=1).min(axis=1)  # ends t = 0, d
        t = np.where(c != 0, -b / (2 * c), np.nan)                                    # vertex of q
        inside = np.isfinite(t) & (t * d > 0) & (np.abs(t) < abs(d))
        r = np.where(inside, np.minimum(r, 1 + (b + c * t) * t / a), r)
    return np.nonzero((a != 0) & (r <= COLLAPSE))[0]


def focal_limits(coef: np.ndarray) -> tuple[float, float, int, int]:
    """``(lo, hi, face_lo, face_hi)``: the first distance below and above 0 where a face collapses
    (``q(t) = COLLAPSE q(0)``; ``-inf`` / ``inf`` and -1 when none does) and those faces."""
    a, b, c = coef.T
    a1 = a * (1 - COLLAPSE)
    with np.errstate(divide="ignore", invalid="ignore"):
        disc = b * b - 4 * a1 * c
        sq = np.sqrt(np.where(disc >= 0, disc, np.nan))
        quad = np.abs(c * a1) > 1e-12 * b * b
        r1 = np.where(quad, (-b - sq) / (2 * c), -a1 / b)
        r2 = np.where(quad, (-b + sq) / (2 * c), np.nan)
    R = np.stack([r1, r2], axis=1)
    R = np.where(np.isfinite(R) & (a != 0)[:, None], R, np.nan)
    pos = np.where(R > 0, R, np.inf).min(axis=1)
    neg = np.where(R < 0, R, -np.inf).max(axis=1)
    if not len(pos):
        return -np.inf, np.inf, -1, -1
    f_hi, f_lo = int(np.argmin(pos)), int(np.argmax(neg))
    hi, lo = float(pos[f_hi]), float(neg[f_lo])
    return lo, hi, (f_lo if np.isfinite(lo) else -1), (f_hi if np.isfinite(hi) else -1)


def turnover_report(mesh: Mesh, normals: np.ndarray, offset: np.ndarray, distances) -> dict:
    """JSON-ready: per layer the count and first ids of the turned-over faces, the safe range (mm)."""
    coef = area_quadratic(mesh, normals, offset)
    lo, hi, f_lo, f_hi = focal_limits(coef)
    per_layer, total = [], set()
    for d in distances:
        f = turned_faces(coef, float(d)) if d != 0 else np.zeros(0, dtype=np.int64)
        total.update(f.tolist())
        per_layer.append({"distance_mm": float(d), "count": int(f.size), "faces": f[:NAMED].tolist()})
    return {"what": "offset faces whose normal flips (the offset goes past the face's focal distance)",
            "count": len(total), "faces": mesh.n_faces, "ok": not total, "per_layer": per_layer,
            "safe_range_mm": [lo if np.isfinite(lo) else None, hi if np.isfinite(hi) else None],
            "first_face_below": f_lo if f_lo >= 0 else None, "first_face_above": f_hi if f_hi >= 0 else None}


def turnover_sentence(t: dict) -> str | None:
    """The loud line of a report whose layers turn faces over (None when none does)."""
    if t["ok"]:
        return None
    lo, hi = t["safe_range_mm"]
    rng = (f"no face turns over between {'-inf' if lo is None else f'{lo:.4g} mm'} and "
           f"{'+inf' if hi is None else f'{hi:+.4g} mm'}")
    bad = [f"{L['count']} of {t['faces']} faces at {L['distance_mm']:g} mm (faces "
           f"{', '.join(map(str, L['faces']))}{', ...' if L['count'] > len(L['faces']) else ''})"
           for L in t["per_layer"] if L["count"]]
    return (f"FACES TURN OVER: {'; '.join(bad)}: the offset goes past the focal distance ({rng}); "
            "those panels and beams cross each other. Use smaller distances, or check the units "
            "(distances are mm).")
