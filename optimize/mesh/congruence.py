"""Which parts are the same part: congruence classes within a tolerance, mirror images as the other hand.

A glass supplier prices and racks by *position* (one shape, a quantity), a
steel shop saws and drills by *type*: what counts is how many different parts
there are.  Two parts are of one class when one can be laid on the other by a
rigid motion (and a relabelling of its corners) so that every corner lies
within ``tol`` (mm) of its match; when it needs a reflection too, it is the
class's other *hand* (a glass unit turned over puts its coating and its
laminate on the wrong side; a node or a beam built as its mirror image does
not fit).

- :func:`ring_classes` classifies ``p`` sets of rings ``X (p, n, k, 2)`` (mm):
  ``n`` polygons of ``k`` corners each, moved together (a glass unit: the
  outline of each of its plies in one frame), relabelled together by a cyclic
  shift of the corners; optional per-corner values ``F (p, n, k, c)`` (mm) that
  travel with the corners and must agree within ``tol`` too (a node: the
  height of each beam direction along the node axis, which a rotation about
  the axis keeps); ``translate=False`` allows rotations about the origin only
  (a node's beam directions).  The mirror image is the rings reflected in the
  y axis with their corners in reverse order (still counter-clockwise).
- :func:`vector_classes` classifies ``p`` descriptors given in each of their
  equivalent spellings ``D (p, v, q)`` (mm): ``v`` spellings of one hand (a
  beam read from either end), then as many of the other (its mirror image).
- :func:`face_rings` gives the faces of a mesh as rings in their own planes, so
  that panels are classified on the mesh (the optimizer's rationalization,
  :mod:`optimize.solvers.rationalize`); ``fabricate.cad.congruence`` classifies
  the glass units, nodes and beams a roof is built from with the same rule.

The test is the best fit in the least-squares sense (2D Kabsch: the centroids
laid on each other, the rotation ``atan2(sum a x b, sum a . b)``), for every
cyclic shift and both hands, then the largest corner distance: a class never
holds two parts further apart than that fit shows (it may split a pair the
min-max fit would join, never join a pair it would split).  Classes are found
by a leader rule, not by chaining: the first part not yet classified (in
input order) opens a class and takes every later unclassified part within
``tol`` of it, so every member lies within ``tol`` of its class's first part,
whose drawing the class's order shows.  Candidates come from a k-d tree over
invariants that move at most ``2 tol`` between congruent parts (sorted edge
lengths and distances from the centroid, sorted per-corner values), so the
work is linear in the parts for a roof of many shapes and for one of few; the
Python loop runs once per class, the fits are array operations.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

TOLERANCE_MM = 1.0
"""Default: parts whose corners all match within 1 mm are one class (a glass cutter's mm)."""

HANDS = ("A", "B")
"""Hand 0 (as the class's first part is drawn) and hand 1 (its mirror image)."""


@dataclass(frozen=True)
class Classes:
    """Congruence classes of ``p`` parts.

    label : (p,) int, class 0..c-1 numbered by their first member.
    hand : (p,) int, 0 laid on the class's first member by a rigid motion, 1 only by its mirror image.
    shift : (p,) int, how its corners are relabelled onto the first member's: corner ``j`` of the
        first member matches corner ``(j + shift) % k`` of this one (of its mirror image for hand 1,
        whose corners run in reverse: corner ``j`` of the mirror is corner ``-j % k``); for
        :func:`vector_classes` the spelling of its hand that matched.
    deviation : (p,) float, mm: largest corner distance from the first member after the fit.
    first : (c,) int: each class's first member.
    tol : the tolerance (mm).
    """

    label: np.ndarray
    hand: np.ndarray
    shift: np.ndarray
    deviation: np.ndarray
    first: np.ndarray
    tol: float

    def __len__(self) -> int:
        return len(self.label)

    @property
    def count(self) -> int:
        """Different parts, mirror images counted as one."""
        return len(self.first)

    @property
    def handed(self) -> np.ndarray:
        """(c,) bool: classes with members of both hands."""
        both = np.zeros((self.count, 2), dtype=bool)
        both[self.label, self.hand] = True
        return both.all(axis=1)

    @property
    def positions(self) -> int:
        """Different parts with mirror images apart (a glass order's positions)."""
        return self.count + int(self.handed.sum())

    @property
    def largest(self) -> int:
        """Members of the largest class (0 without parts)."""
        return int(np.bincount(self.label).max()) if len(self.label) else 0

    def names(self, prefix: str) -> list[str]:
        """(p,) the type of every part: ``<prefix>007``, and ``<prefix>007A`` / ``B`` where the class has
        both hands (3 digits at least)."""
        width = max(3, len(str(self.count)))
        handed = self.handed
        return [f"{prefix}{c + 1:0{width}d}{HANDS[h] if handed[c] else ''}"
                for c, h in zip(self.label.tolist(), self.hand.tolist())]

    def summary(self) -> dict:
        """JSON-ready counts."""
        return {"parts": len(self), "types": self.count, "with_hands": self.positions,
                "handed_types": int(self.handed.sum()), "most_of_one_type": self.largest,
                "largest_deviation_mm": float(self.deviation.max()) if len(self) else 0.0, "tolerance_mm": self.tol}


def empty(tol: float) -> Classes:
    z = np.zeros(0, dtype=np.int64)
    return Classes(z, z, z, np.zeros(0), z, float(tol))


def merge(parts: list[tuple[np.ndarray, Classes]], p: int) -> Classes:
    """One :class:`Classes` of ``p`` parts from classes of disjoint subsets ``(index (q,), classes)``
    (parts that cannot match: other corner counts, valences), renumbered by first member."""
    if not parts:
        return empty(TOLERANCE_MM)
    label = np.full(p, -1, dtype=np.int64)
    hand = np.zeros(p, dtype=np.int64)
    shift = np.zeros(p, dtype=np.int64)
    dev = np.zeros(p)
    firsts, base = [], 0
    for index, c in parts:  # a few subsets (corner counts)
        label[index] = c.label + base
        hand[index], shift[index], dev[index] = c.hand, c.shift, c.deviation
        firsts.append(index[c.first])
        base += c.count
    first = np.concatenate(firsts) if firsts else np.zeros(0, dtype=np.int64)
    if (label < 0).any():
        raise ValueError(f"merge: {int((label < 0).sum())} of {p} parts in no subset")
    order = np.argsort(first, kind="stable")               # classes numbered by their first member
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return Classes(rank[label], hand, shift, dev, first[order], parts[0][1].tol)


def _leaders(keys: np.ndarray, radius: float, tol: float,
             fit: Callable[[int, np.ndarray], tuple[np.ndarray, np.ndarray]]) -> Classes:
    """Leader classification: ``keys (p, q)`` invariants (congruent parts within ``radius``, inf-norm);
    ``fit(i, J)`` -> ``deviation (j, 2)`` per hand and ``shift (j, 2)`` of parts ``J`` from part ``i``."""
    from scipy.spatial import cKDTree

    p = len(keys)
    label = np.full(p, -1, dtype=np.int64)
    hand = np.zeros(p, dtype=np.int64)
    shift = np.zeros(p, dtype=np.int64)
    dev = np.zeros(p)
    if p == 0:
        return empty(tol)
    tree = cKDTree(keys)
    firsts: list[int] = []
    for i in range(p):  # a leader per class; members are classified in one array fit
        if label[i] >= 0:
            continue
        J = np.asarray(tree.query_ball_point(keys[i], radius * (1 + 1e-9) + 1e-9, p=np.inf), dtype=np.int64)
        J = J[(label[J] < 0) & (J != i)]
        c = len(firsts)
        firsts.append(i)
        label[i] = c
        if not len(J):
            continue
        d, s = fit(i, J)
        h = np.where(d[:, 0] <= tol, 0, 1)
        ok = d[np.arange(len(J)), h] <= tol
        J, h = J[ok], h[ok]
        label[J], hand[J] = c, h
        shift[J], dev[J] = s[ok, h], d[ok, h]
    return Classes(label, hand, shift, dev, np.asarray(firsts, dtype=np.int64), float(tol))


def mirror_rings(X: np.ndarray) -> np.ndarray:
    """``X (..., k, 2)`` reflected in the y axis, corners in reverse order from corner 0 (ccw stays ccw)."""
    k = X.shape[-2]
    return (X * np.array([-1.0, 1.0]))[..., (-np.arange(k)) % k, :]


def _ring_keys(X: np.ndarray, F: np.ndarray | None, translate: bool) -> np.ndarray:
    p = len(X)
    L = np.linalg.norm(np.roll(X, -1, axis=2) - X, axis=3)                      # (p, n, k) edge lengths
    c = X.reshape(p, -1, 2).mean(axis=1)[:, None, None, :] if translate else 0.0
    R = np.linalg.norm(X - c, axis=3)                                           # distances from the centre
    keys = [np.sort(L, axis=2).reshape(p, -1), np.sort(R, axis=2).reshape(p, -1)]
    if F is not None:
        keys.append(np.sort(F, axis=2).reshape(p, -1))
    return np.concatenate(keys, axis=1)


def ring_deviation(A: np.ndarray, Y: np.ndarray, FA: np.ndarray | None = None, FY: np.ndarray | None = None,
                   translate: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """How far ring sets ``Y (m, n, k, 2)`` are from ``A (n, k, 2)`` (mm): for every cyclic relabelling
    ``s`` of the corners (corner ``j`` of ``A`` against corner ``(j + s) % k`` of ``Y``) the least-squares
    rigid fit (a rotation about the centroids, or about the origin with ``translate=False``), then the
    largest corner distance, and of per-corner values ``FA (n, k, c)`` / ``FY (m, n, k, c)`` the largest
    difference.  Returns ``deviation (m,)`` and ``shift (m,)`` of the best relabelling (no reflection:
    compare :func:`mirror_rings` of ``Y`` for the other hand)."""
    A = np.asarray(A, dtype=float)
    Y = np.asarray(Y, dtype=float)
    m, n, k = Y.shape[:3]
    if A.shape != Y.shape[1:]:
        raise ValueError(f"ring_deviation: A {A.shape} and Y {Y.shape} differ in rings or corners")
    idx = (np.arange(k)[:, None] + np.arange(k)[None, :]) % k                   # [shift, j] -> corner
    A = A.reshape(n * k, 2)
    Ys = np.moveaxis(Y[:, :, idx], 2, 1).reshape(m, k, n * k, 2)               # (m, shift, points, 2)
    if translate:
        A = A - A.mean(axis=0)
        Ys = Ys - Ys.mean(axis=2, keepdims=True)
    cross = (Ys[..., 0] * A[:, 1] - Ys[..., 1] * A[:, 0]).sum(axis=-1)
    th = np.arctan2(cross, (Ys * A).sum(axis=(-1, -2)))[..., None]             # rotates Y onto A
    c, s = np.cos(th), np.sin(th)
    d = np.hypot(c * Ys[..., 0] - s * Ys[..., 1] - A[:, 0], s * Ys[..., 0] + c * Ys[..., 1] - A[:, 1]).max(axis=-1)
    if FA is not None and FY is not None:
        G = np.moveaxis(np.asarray(FY, dtype=float)[:, :, idx], 2, 1).reshape(m, k, n * k, -1)
        d = np.maximum(d, np.abs(G - np.asarray(FA, dtype=float).reshape(n * k, -1)).max(axis=(-1, -2)))
    best = d.argmin(axis=1)
    return d[np.arange(m), best], best


def ring_classes(X: np.ndarray, tol: float = TOLERANCE_MM, F: np.ndarray | None = None,
                 translate: bool = True) -> Classes:
    """Congruence classes of ring sets ``X (p, n, k, 2)`` mm (``n`` polygons of ``k`` corners moved and
    relabelled together), with per-corner values ``F (p, n, k, c)`` mm that must agree too; rigid
    motions in the plane (``translate=False``: rotations about the origin).  See the module text."""
    X = np.asarray(X, dtype=float)
    k = X.shape[2]
    if F is not None:
        F = np.asarray(F, dtype=float)
        if F.shape[:3] != X.shape[:3]:
            raise ValueError(f"ring_classes: F {F.shape} does not match X {X.shape}")
    Xm = mirror_rings(X)
    Fm = None if F is None else F[:, :, (-np.arange(k)) % k]

    def fit(i: int, J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        FA = None if F is None else F[i]
        d0, s0 = ring_deviation(X[i], X[J], FA, None if F is None else F[J], translate)
        d1, s1 = ring_deviation(X[i], Xm[J], FA, None if Fm is None else Fm[J], translate)
        return np.stack([d0, d1], axis=1), np.stack([s0, s1], axis=1)

    return _leaders(_ring_keys(X, F, translate), 2.0 * tol, tol, fit)


def vector_classes(D: np.ndarray, tol: float = TOLERANCE_MM, spellings: int | None = None) -> Classes:
    """Classes of descriptors ``D (p, v, q)`` mm: part ``j`` matches part ``i`` (as spelt first) when
    one of its spellings is within ``tol`` of it in every entry.  Spellings ``0 .. spellings-1`` are
    hand 0, the rest (if any) its mirror image.  Candidates: the entries sorted over the spellings
    (invariant under the respelling, moved at most ``tol`` each)."""
    D = np.asarray(D, dtype=float)
    p, v, q = D.shape
    spellings = v if spellings is None else spellings
    own = np.arange(v) < spellings

    def fit(i: int, J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        d = np.abs(D[J] - D[i, 0]).max(axis=2)                                   # (j, v)
        out, best = np.full((len(J), 2), np.inf), np.zeros((len(J), 2), dtype=np.int64)
        for h, sel in enumerate((own, ~own)):  # the two hands
            if sel.any():
                cols = np.flatnonzero(sel)
                b = d[:, cols].argmin(axis=1)
                out[:, h], best[:, h] = d[np.arange(len(J)), cols[b]], cols[b]
        return out, best

    keys = np.sort(D, axis=1).reshape(p, -1)
    return _leaders(keys, tol, tol, fit)


def face_rings(mesh, V: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """The faces of ``mesh`` (positions ``V (n, 3)``, the mesh's own when None) as rings for
    :func:`ring_classes`, one entry per corner count: ``(faces (q,), X (q, 1, k, 2))``, every face's
    corners in the frame of its best-fit plane (origin at the corners' mean, axes from the
    singular vectors, counter-clockwise seen from the face's normal side)."""
    V = mesh.V if V is None else np.asarray(V, dtype=float)
    sizes = mesh.face_sizes
    out = []
    for k in np.unique(sizes).tolist():
        faces = np.nonzero(sizes == k)[0]
        P = V[mesh.F[faces, :k]]                                                  # (q, k, 3)
        D = P - P.mean(axis=1, keepdims=True)
        _, _, Wt = np.linalg.svd(D)
        X = np.einsum("qkj,qij->qki", D, Wt[:, :2])                               # (q, k, 2)
        N = np.cross(D, np.roll(D, -1, axis=1)).sum(axis=1)                       # the face's normal side
        flip = np.einsum("qj,qj->q", np.cross(Wt[:, 0], Wt[:, 1]), N) < 0
        X[flip, :, 1] *= -1.0                                                     # counter-clockwise rings
        out.append((faces, X[:, None]))
    return out


def face_classes(mesh, V: np.ndarray | None = None, tol: float = TOLERANCE_MM) -> Classes:
    """Congruence classes of the faces of ``mesh`` (positions ``V``, in its units) within ``tol``
    at every corner (:func:`ring_classes` of :func:`face_rings`; mirror images the other hand)."""
    return merge([(faces, ring_classes(X, tol)) for faces, X in face_rings(mesh, V)], mesh.n_faces)
