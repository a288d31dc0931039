"""What is drawn for every flat part: outline, bevel outline, id text and orientation arrow.

All in the part's own plane (``PartGroup.flat``: exact edge lengths, seen
from outside the part, counter-clockwise), shared by the DXF and SVG
writers.  The arrow points from the id toward the outline edge shared with
the part's face 2: for a panel, the side over the mesh face's first edge
(corner 0 -> 1); for a beam, the glass-side (first layer) edge.  Together
with the counter-clockwise outline it fixes which way up the part goes.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FlatGroup:
    """Drawing data of one :class:`fabricate.cad.PartGroup` (``p`` parts).

    outline : (p, k, 2).  bevel : (p, k2, 2) or None.  arrow : (p, 5, 2) polyline
    (tail, tip, barb, tip, barb).  text_at : (p, 2) centre of the id.
    text_height : (p,) mm.
    """

    outline: np.ndarray
    bevel: np.ndarray | None
    arrow: np.ndarray
    text_at: np.ndarray
    text_height: np.ndarray


def mark_edge(faces: tuple[tuple[int, ...], ...], outline_face: int) -> int:
    """Position ``j`` of the outline edge (``j -> j + 1``) shared with ``faces[2]``."""
    f = faces[outline_face]
    other = set(faces[2])
    for j in range(len(f)):
        if f[j] in other and f[(j + 1) % len(f)] in other:
            return j
    return 0


def flat_group(group) -> FlatGroup:
    """The drawing data of every part of ``group`` (vectorized over parts)."""
    Q = group.flat
    j = mark_edge(group.faces, group.outline_face)
    k = Q.shape[1]
    centre = Q.mean(axis=1)
    mid = 0.5 * (Q[:, j] + Q[:, (j + 1) % k])
    d = mid - centre
    h = np.clip(0.12 * group.rect[:, 1], 2.0, 60.0)
    tail = centre + 0.35 * d
    tip = centre + 0.8 * d
    u = d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    perp = np.stack([-u[:, 1], u[:, 0]], axis=1)
    barb = 0.6 * h[:, None]
    arrow = np.stack([tail, tip, tip - barb * (u + 0.5 * perp), tip, tip - barb * (u - 0.5 * perp)], axis=1)
    bevel = group.flat_bevel
    if bevel is not None:  # drop a bevel outline that coincides with the outline (square edges)
        gap = np.linalg.norm(bevel[:, :, None, :] - Q[:, None, :, :], axis=3).min(axis=2).max()
        bevel = None if gap < 1e-6 else bevel
    return FlatGroup(outline=Q, bevel=bevel, arrow=arrow, text_at=centre, text_height=h)
