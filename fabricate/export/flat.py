"""What is drawn for every flat part: outline, bevel outline, id text and orientation arrow.

All in the part's own plane (``PartGroup.flat``: exact edge lengths, seen
from outside the part, counter-clockwise), shared by the DXF and SVG
writers.  The arrow points from the id toward the outline edge shared with
the part's face 2: for a panel, the side over the mesh face's first edge
(corner 0 -> 1); for a beam, the glass-side (first layer) edge.  Together
with the counter-clockwise outline it fixes which way up the part goes.
The data of a group is made once per group object (weakly cached, like the layouts
of :mod:`fabricate.export.nesting`).
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FlatGroup:
    """Drawing data of one :class:`fabricate.cad.PartGroup` (``p`` parts).

    outline : (p, k, 2) the CUT line.  bevels : tuple of (p, k_i, 2) closed lines drawn
    dashed where they differ from it: the bevel reference (panel bearing face; beam ridge and
    V tips) and the two sheet faces (where the bevels end).  arrow : (p, 5, 2) polyline
    (tail, tip, barb, tip, barb).  text_at : (p, 2) centre of the id.
    text_height : (p,) mm.  angle_at : (p, k, 2) where each edge's bevel label goes;
    angle_text : (p, k) str, ``"+a/-b"`` degrees on the +z / -z side (``"0"`` square).
    """

    outline: np.ndarray
    bevels: tuple
    arrow: np.ndarray
    text_at: np.ndarray
    text_height: np.ndarray
    angle_at: np.ndarray
    angle_text: np.ndarray


def mark_edge(faces: tuple[tuple[int, ...], ...], outline_face: int) -> int:
    """Position ``j`` of the outline edge (``j -> j + 1``) shared with ``faces[2]``."""
    f = faces[outline_face]
    other = set(faces[2])
    for j in range(len(f)):
        if f[j] in other and f[(j + 1) % len(f)] in other:
            return j
    return 0


_FLAT: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""Drawing data per group, made once: the outline DXF and SVG and each nested cut file draw the same groups."""


def flat_group(group) -> FlatGroup:
    """The drawing data of every part of ``group`` (vectorized over parts; made once per group object)."""
    try:
        return _FLAT[group]
    except KeyError:
        pass
    except TypeError:  # not weak-referenceable: no cache
        return _flat_group(group)
    fg = _FLAT[group] = _flat_group(group)
    return fg


def _flat_group(group) -> FlatGroup:
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
    bevels = []
    for line in (group.bevel_ref,) + tuple(group.flat_faces):  # drop lines on the cut line (square edges)
        if _off_outline(line, Q) and not any(line.shape == b.shape and np.abs(line - b).max() < 1e-6
                                             for b in bevels):
            bevels.append(line)
    mids = 0.5 * (Q + np.concatenate([Q[:, 1:], Q[:, :1]], axis=1))
    angle_at = mids + 0.25 * (centre[:, None, :] - mids)
    angle_text = angle_labels(group.bevel_deg[..., 0], group.bevel_deg[..., 1])
    return FlatGroup(outline=Q, bevels=tuple(bevels), arrow=arrow, text_at=centre, text_height=h,
                     angle_at=angle_at, angle_text=angle_text)


def _off_outline(line: np.ndarray, Q: np.ndarray) -> bool:
    """Whether some point of ``line (p, m, 2)`` is more than 1e-6 mm from every corner of ``Q (p, k, 2)``.

    Decided on the squared distances (their sqrt taken once, after the min and max: the same figure
    as the norm of each).  The first part decides most groups; else each point's distance from the
    corner nearest it on the first part bounds its distance from the nearest corner, and only the
    parts that bound leaves open are measured in full."""
    if not line.size or not Q.size:
        return False

    def d2(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        D = a - b
        return D[..., 0] * D[..., 0] + D[..., 1] * D[..., 1]

    first = d2(line[:1, :, None, :], Q[:1, None, :, :])[0]                    # (m, k)
    if np.sqrt(first.min(axis=1).max()) > 1e-6:
        return True
    near = Q[:, first.argmin(axis=1)]                                          # (p, m, 2)
    bound = d2(line, near).max(axis=1)                                         # (p,)
    open_ = np.sqrt(bound) > 1e-6
    if not open_.any():
        return False
    full = d2(line[open_][:, :, None, :], Q[open_][:, None, :, :])
    return bool(np.sqrt(full.min(axis=2).max()) > 1e-6)


def angle_labels(top: np.ndarray, bottom: np.ndarray) -> np.ndarray:
    """Bevel labels ``(p, k) str`` of edges with angles ``top, bottom (p, k)``: :func:`_angles` of each,
    the square edges (most) found at once, only the others formatted."""
    top, bottom = np.asarray(top, dtype=float), np.asarray(bottom, dtype=float)
    square = (np.abs(top) < 0.05) & (np.abs(bottom) < 0.05)
    one = ~square & (np.abs(top + bottom) < 0.05)
    two = ~square & ~one
    out = np.full(top.shape, "0", dtype=object)
    out[one] = [f"{t:+.1f}" for t in top[one].tolist()]
    out[two] = [f"{t:+.1f}/{b:+.1f}" for t, b in zip(top[two].tolist(), bottom[two].tolist())]
    return out.astype(str) if out.size else np.zeros(top.shape, dtype="<U1")


def _angles(top: float, bottom: float) -> str:
    """Bevel label of one edge: degrees on the +z / -z side, ``0`` for a square edge."""
    if abs(top) < 0.05 and abs(bottom) < 0.05:
        return "0"
    if abs(top + bottom) < 0.05:
        return f"{top:+.1f}"       # one plane through the thickness
    return f"{top:+.1f}/{bottom:+.1f}"
