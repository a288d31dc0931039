"""Which parts are the same part: congruence classes of glass units, nodes and beams.

The rule and the classifiers (:func:`ring_classes`, :func:`vector_classes`,
:class:`Classes`: congruent within ``tol`` mm at every corner after the best
rigid fit, mirror images the other hand, a leader rule without chaining) live
in :mod:`optimize.mesh.congruence`, where the optimizer classifies mesh faces
with them; this module gives the rings of a roof's glass units
(:func:`glass_unit_rings`: every ply's cut outline and bearing line, in the
frame of the ply on the beams) and their classes (:func:`glass_classes`).
"""
from __future__ import annotations

import numpy as np

from optimize.mesh.congruence import (  # noqa: F401 (re-exported: the schedules, the order, the totals)
    HANDS,
    TOLERANCE_MM,
    Classes,
    empty,
    merge,
    mirror_rings,
    ring_classes,
    ring_deviation,
    vector_classes,
)


def glass_unit_rings(parts) -> tuple[list[str], np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
    """The rings of every glass unit, for :func:`ring_classes`.

    Returns ``ids (u,)`` the unit ids (of the ply on the beams, ``P0001``), ``element (u,)`` their mesh
    faces, and per corner count ``(index (q,), X (q, n, k, 2))``: for each glass ply outside in (no
    interlayers) its cut outline (``PartGroup.flat``) and its bearing line (``bevel_ref``), in the flat
    frame of the unit's ply on the beams (:func:`bearing_groups`), corner ``j`` of every ring over
    corner ``j`` of the bearing ply."""
    from .glass import bearing_groups
    from .parts import unit_id

    units = bearing_groups(parts)
    ids = [unit_id(i) for g in units for i in g.ids]
    element = np.concatenate([g.element for g in units]) if units else np.zeros(0, dtype=np.int64)
    plies = [g for g in parts.of_kind("panel") if not g.material]
    order = {m.member: j for j, m in enumerate(parts.spec.glass.solids())} if hasattr(parts.spec, "glass") else {}
    plies.sort(key=lambda g: order.get(g.member, 0))                             # outside in, stable
    n_faces = 1 + int(element.max()) if len(element) else 0
    out, start = [], 0
    for b in units:  # one bearing group per corner count
        k = b.flat.shape[1]
        row = np.full(n_faces, -1, dtype=np.int64)
        row[b.element] = np.arange(len(b))
        Minv = np.linalg.inv(b.transform)                                        # model -> bearing frame
        rings = []
        for member in dict.fromkeys(g.member for g in plies):  # plies outside in
            X = np.full((len(b), 2, k, 2), np.nan)
            for g in plies:
                if g.member != member or g.flat.shape[1] != k:
                    continue
                sel = g.element < n_faces
                r = np.where(sel, row[np.minimum(g.element, n_faces - 1)], -1)
                got = r >= 0
                for j, P in enumerate((g.flat, g.bevel_ref)):  # the outline and the bearing line
                    H = np.concatenate([P[got], np.zeros(P[got].shape[:2] + (1,)), np.ones(P[got].shape[:2] + (1,))],
                                       axis=2)
                    W = np.einsum("pij,pkj->pki", g.transform[got], H)            # to the model
                    B = np.einsum("pij,pkj->pki", Minv[r[got]], W)                # to the bearing frame
                    X[r[got], j] = B[..., :2]
            if np.isnan(X).all():
                continue
            if np.isnan(X).any():
                raise ValueError(f"glass unit rings: ply {member!r} missing on some units of {k} corners")
            rings.append(X)
        out.append((np.arange(start, start + len(b)), np.concatenate(rings, axis=1)))
        start += len(b)
    return ids, element, out


def glass_classes(parts, tol: float = TOLERANCE_MM) -> tuple[list[str], Classes]:
    """The unit ids (:func:`glass_unit_rings`) and their classes: one class per glass shape (every ply's
    outline and bearing line within ``tol``), mirror images its other hand."""
    ids, _, rings = glass_unit_rings(parts)
    return ids, merge([(index, ring_classes(X, tol)) for index, X in rings], len(ids))
