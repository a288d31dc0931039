"""Beam ends on their nodes, measured on a written model (issue 34): read the 3MF back and, for every
beam solid, find its end faces and how far each point of them lies from the parts of the node it ends at.

A beam solid's faces run along its edge (web and flange faces, whose planes contain the beam's
direction) except at its two ends; its end faces are the triangles whose normal leans more than
:data:`END_COS` along the beam (the principal direction of its vertices), split into the two ends by
the sign, where the beam's direction is from one to the other of the two nodes nearest to it (hub
tube and cap plates, ``N0001.k`` -> ``N0001``: their centroids), and each end to its node;
its points (the triangles' corners, edge midpoints and centroids) are measured against that node's
triangles (the distance to its surface).  A coped end lies on the tube's facets: 0 mm; a square end at
the hub radius stands off where the plate is off the beam plane (a web 45 mm off, on a 110 mm tube:
9.2 mm).  Without node parts (mitred ends, ``connection: none``) there is nothing to measure.
"""
from __future__ import annotations

import numpy as np

END_COS = 0.25
"""A triangle is an end face when ``|normal . direction| >`` this (75.5 deg from the beam's faces:
a cope onto a tube's facet leans at most ``asin(half width / radius)``)."""

CHUNK = 256
"""Points measured at a time (memory: ``CHUNK x node triangles x 9`` floats)."""


def closest_on_triangles(P: np.ndarray, A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Distance ``(m, t)`` from points ``P (m, 3)`` to the triangles ``(A, B, C)`` ``(m, t, 3)`` each
    (Ericson, Real-Time Collision Detection 5.1.5, by Voronoi region, vectorized)."""
    P = P[:, None, :]
    ab, ac, ap = B - A, C - A, P - A
    d1, d2 = (ab * ap).sum(-1), (ac * ap).sum(-1)
    bp = P - B
    d3, d4 = (ab * bp).sum(-1), (ac * bp).sum(-1)
    cp = P - C
    d5, d6 = (ab * cp).sum(-1), (ac * cp).sum(-1)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = np.where(denom != 0, vb / denom, 0.0)
        w = np.where(denom != 0, vc / denom, 0.0)
        Q = A + v[..., None] * ab + w[..., None] * ac                     # inside the face
        t_ab = np.clip(d1 / np.where(d1 - d3 != 0, d1 - d3, 1.0), 0, 1)
        t_ac = np.clip(d2 / np.where(d2 - d6 != 0, d2 - d6, 1.0), 0, 1)
        t_bc = np.clip((d4 - d3) / np.where((d4 - d3) + (d5 - d6) != 0, (d4 - d3) + (d5 - d6), 1.0), 0, 1)
    rules = [  # (region, closest point), first match wins (Ericson's order)
        ((d1 <= 0) & (d2 <= 0), A),
        ((d3 >= 0) & (d4 <= d3), B),
        ((vc <= 0) & (d1 >= 0) & (d3 <= 0), A + t_ab[..., None] * ab),
        ((d6 >= 0) & (d5 <= d6), C),
        ((vb <= 0) & (d2 >= 0) & (d6 <= 0), A + t_ac[..., None] * ac),
        ((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), B + t_bc[..., None] * (C - B)),
    ]
    for mask, X in reversed(rules):
        Q = np.where(mask[..., None], X, Q)
    return np.linalg.norm(P - Q, axis=-1)


def _stack(objects: dict, prefix: str) -> list[tuple[list[str], np.ndarray, np.ndarray]]:
    """Objects whose name starts with ``prefix``, stacked by identical triangle lists:
    ``[(names, V (p, nv, 3), T (t, 3))]``."""
    by: dict[bytes, tuple[list, list, np.ndarray]] = {}
    for name, (V, T) in objects.items():
        if not str(name).startswith(prefix):
            continue
        key = np.asarray(T, dtype=np.int64).tobytes() + bytes(str(len(V)), "ascii")
        row = by.setdefault(key, ([], [], np.asarray(T, dtype=np.int64)))
        row[0].append(str(name))
        row[1].append(np.asarray(V, dtype=float))
    return [(names, np.stack(Vs), T) for names, Vs, T in by.values()]


def _node_triangles(objects: dict) -> tuple[list[str], np.ndarray]:
    """Node units (``N0001``) and their triangles ``(n, t, 3, 3)`` (every part of the unit)."""
    units: dict[str, list[np.ndarray]] = {}
    for names, V, T in _stack(objects, "N"):
        tris = V[:, T]                                                    # (p, t, 3, 3)
        for name, tr in zip(names, tris):
            units.setdefault(name.split(".", 1)[0], []).append(tr)
    ids = sorted(units)
    per = [np.concatenate(units[i]) for i in ids]
    t = max((len(x) for x in per), default=0)
    out = np.empty((len(ids), t, 3, 3))
    for k, x in enumerate(per):                       # pad a smaller node with its own first triangle
        out[k, :len(x)] = x
        out[k, len(x):] = x[0]
    return ids, out


def end_gaps(objects: dict, tol_mm: float = 1.0) -> dict:
    """How far the beam end faces of a read model stand off their nodes (mm).

    objects : ``{name: (V (nv, 3), T (t, 3))}`` (:func:`fabricate.export.threemf.read_3mf`).
    Returns ``{"ends": count of end faces measured, "nodes": node units, "worst_mm", "worst_id"
    (beam solid id), "worst_node", "over": [(beam solid id, node id, mm)] of the ends standing off more
    than ``tol_mm`` (worst first), "tol_mm", "per_end": (ids, node ids, mm) arrays}``;
    ``ends`` 0 without node parts.
    """
    node_ids, NT = _node_triangles(objects)
    empty = {"ends": 0, "nodes": len(node_ids), "worst_mm": 0.0, "worst_id": "", "worst_node": "", "over": [],
             "tol_mm": float(tol_mm), "per_end": ([], [], np.zeros(0))}
    if not node_ids:
        return empty
    centre = NT.reshape(len(NT), -1, 3).mean(axis=1)
    pts, owner, names, node_of_end = [], [], [], []
    for bnames, V, T in _stack(objects, "B"):
        tri = V[:, T]                                                     # (p, t, 3, 3)
        n = np.cross(tri[:, :, 1] - tri[:, :, 0], tri[:, :, 2] - tri[:, :, 0])
        area2 = np.linalg.norm(n, axis=-1)
        n = n / np.maximum(area2, 1e-300)[..., None]
        ends = _two_nearest(V.mean(axis=1), centre)                       # (p, 2): the nodes it runs between
        along = centre[ends[:, 1]] - centre[ends[:, 0]]
        along /= np.maximum(np.linalg.norm(along, axis=1), 1e-300)[:, None]
        c = (n * along[:, None, :]).sum(-1)
        sample = np.concatenate([tri, 0.5 * (tri + np.roll(tri, -1, axis=2)), tri.mean(axis=2, keepdims=True)],
                                axis=2)                                   # (p, t, 7, 3)
        for k, sgn in ((0, -1.0), (1, 1.0)):                              # faces toward node 0, node 1
            end = (sgn * c > END_COS) & (area2 > 1e-9)
            for i in np.flatnonzero(end.any(axis=1)):                     # one end of one solid
                P = sample[i, end[i]].reshape(-1, 3)
                pts.append(P)
                owner.append(np.full(len(P), len(names)))
                names.append(bnames[i])
                node_of_end.append(ends[i, k])
    if not names:
        return empty
    P = np.concatenate(pts)
    own = np.concatenate(owner)
    node_of_end = np.array(node_of_end)
    node_of = node_of_end[own]
    gap = np.empty(len(P))
    for s in range(0, len(P), CHUNK):
        tr = NT[node_of[s:s + CHUNK]]
        gap[s:s + CHUNK] = closest_on_triangles(P[s:s + CHUNK], tr[:, :, 0], tr[:, :, 1], tr[:, :, 2]).min(axis=1)
    worst = np.full(len(names), -np.inf)
    np.maximum.at(worst, own, gap)
    k = int(np.argmax(worst))
    order = np.argsort(-worst)
    over = [(names[j], node_ids[node_of_end[j]], float(worst[j])) for j in order if worst[j] > tol_mm]
    return {"ends": len(names), "nodes": len(node_ids), "worst_mm": float(worst[k]), "worst_id": names[k],
            "worst_node": node_ids[node_of_end[k]], "over": over, "tol_mm": float(tol_mm),
            "per_end": (names, [node_ids[j] for j in node_of_end], worst)}


def _two_nearest(X: np.ndarray, C: np.ndarray) -> np.ndarray:
    """``(p, 2)``: the two rows of ``C`` nearest to every row of ``X`` (in blocks: memory)."""
    out = np.empty((len(X), 2), dtype=np.int64)
    step = max(1, int(2e7 // max(len(C), 1)))
    for s in range(0, len(X), step):
        d2 = ((X[s:s + step, None, :] - C[None]) ** 2).sum(-1)
        out[s:s + step] = np.argsort(d2, axis=1)[:, :2] if len(C) > 1 else 0
    return out


def check_beam_ends(path, tol_mm: float = 1.0) -> dict:
    """:func:`end_gaps` of the 3MF file ``path`` (``fabricate.export.threemf.read_3mf``), plus ``ok``:
    every point of every beam end face within ``tol_mm`` of its node's parts (True without nodes)."""
    from .threemf import read_3mf

    out = end_gaps(read_3mf(path), tol_mm)
    out["ok"] = not out["over"]
    return out
