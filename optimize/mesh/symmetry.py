"""The rigid symmetries of a mesh: detected, measured and imposed.

A symmetry of a mesh is a rigid map ``x -> R x + t`` (a rotation, a mirror or a
rotoreflection; ``R (3, 3)`` orthogonal) together with a vertex permutation ``P``
such that ``V[P] = V R^T + t`` within a tolerance and every face is mapped onto a
face.  The symmetries of a finite mesh fix its vertex centroid ``c``, so ``t = c - R c``.

:func:`detect` finds them: it picks two anchor vertices ``a, b`` whose rigid
invariants (distance from ``c``, valence, sorted edge lengths of the star) are
rarest, and for every pair of vertices ``(a', b')`` with the same invariants and
``|a' - b'| = |a - b|`` tries the rotation and the reflection carrying
``(a - c, b - c)`` onto ``(a' - c, b' - c)``; a candidate is kept when every vertex
lands within the tolerance of a distinct vertex and the faces map onto faces.  The
maps found are closed under composition (:class:`Group`).  Translational
repetition of a finite roof (a vault whose bays repeat) is no symmetry of the
mesh (its ends differ): rationalization (:mod:`optimize.solvers.rationalize`)
pulls such panels into one class.

:meth:`Group.symmetrize` is the Reynolds projection ``V_sym = mean_g R_g^T
(V[P_g] - t_g)``: the nearest symmetric positions in the mean-square sense.  The
planarity, conical and circular conditions are invariant under the group, so the
projection of a nearly symmetric solution is a solution to first order
(``optimize.api`` then re-solves and projects again).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .core import Mesh

TOLERANCE = 1e-7
"""Default: a map is a symmetry when every vertex lands within this fraction of the bounding-box
diagonal of a vertex (a design built from formulas is symmetric to about 1e-13)."""
MAX_CANDIDATES = 4096
"""Anchor images tried at most (rotation and reflection each); a mesh with more equivalent
anchors (a sphere-like vertex set) is searched among the first ones only."""


@dataclass(frozen=True)
class Symmetry:
    """One rigid symmetry: ``V[perm] = V @ R.T + t`` (within the group's tolerance).

    R : (3, 3) orthogonal.  t : (3,).  perm : (n,) int vertex permutation.
    faces : (m,) int, face ``f`` is mapped onto face ``faces[f]``.
    """

    R: np.ndarray
    t: np.ndarray
    perm: np.ndarray
    faces: np.ndarray

    @property
    def kind(self) -> str:
        """``identity``, ``rotation`` (det 1), ``mirror`` (a reflection in a plane) or ``rotoreflection``."""
        det = float(np.linalg.det(self.R))
        tr = float(np.trace(self.R))
        if det > 0:
            return "identity" if tr > 3 - 1e-9 else "rotation"
        return "mirror" if tr > 1 - 1e-9 else "rotoreflection"


@dataclass(frozen=True)
class Group:
    """The symmetries of a mesh, the identity first (every one :func:`detect` found: a group).

    maps : tuple of :class:`Symmetry`.  tol : the absolute tolerance they were found with.
    """

    maps: tuple[Symmetry, ...]
    tol: float

    @property
    def order(self) -> int:
        return len(self.maps)

    @property
    def trivial(self) -> bool:
        return self.order <= 1

    def kinds(self) -> dict[str, int]:
        """How many maps of each kind (identity, rotation, mirror, rotoreflection)."""
        out: dict[str, int] = {}
        for g in self.maps:
            out[g.kind] = out.get(g.kind, 0) + 1
        return out

    def deviation(self, V: np.ndarray) -> float:
        """Largest distance ``|V[P_g] - (V R_g^T + t_g)|`` over the maps, for positions ``V (n, 3)``."""
        return max((float(np.linalg.norm(V[g.perm] - (V @ g.R.T + g.t), axis=1).max(initial=0.0))
                    for g in self.maps), default=0.0)

    def symmetrize(self, V: np.ndarray) -> np.ndarray:
        """``(n, 3)``: the group average of ``V (n, 3)``, exactly symmetric up to rounding."""
        acc = np.zeros_like(V, dtype=float)
        for g in self.maps:
            acc += (V[g.perm] - g.t) @ g.R  # R^T applied to each row
        return acc / self.order

    def orbits(self, which: str = "faces") -> np.ndarray:
        """``(m,)`` or ``(n,)`` int: the orbit label of every face (``which="faces"``) or vertex,
        numbered by their lowest member."""
        idx = [g.faces if which == "faces" else g.perm for g in self.maps]
        size = len(idx[0]) if idx else 0
        images = np.stack(idx) if idx else np.zeros((0, 0), dtype=np.int64)
        low = images.min(axis=0) if len(images) else np.arange(size)
        _, label = np.unique(low, return_inverse=True)
        return label

    def summary(self) -> dict:
        """JSON-ready: order and kinds."""
        return {"order": self.order, "kinds": self.kinds(), "tolerance": self.tol}


def trivial(mesh: Mesh) -> Group:
    """The group of the identity alone."""
    n, m = mesh.n_vertices, mesh.n_faces
    return Group((Symmetry(np.eye(3), np.zeros(3), np.arange(n), np.arange(m)),), 0.0)


def _face_keys(F: np.ndarray) -> np.ndarray:
    """(m, k) int: every face's vertex indices sorted (padding -1 first): a key of its vertex set."""
    return np.sort(F, axis=1)


def _face_map(F: np.ndarray, perm: np.ndarray) -> np.ndarray | None:
    """(m,) int: the face each face is mapped onto under the vertex permutation ``perm``; None when
    some face's image is no face."""
    keys = _face_keys(F)
    mapped = _face_keys(np.where(F >= 0, perm[np.maximum(F, 0)], -1))
    order = np.lexsort(keys.T[::-1])
    sk = keys[order]
    morder = np.lexsort(mapped.T[::-1])
    sm = mapped[morder]
    if not np.array_equal(sk, sm):
        return None
    out = np.empty(len(F), dtype=np.int64)
    out[morder] = order
    return out


def _invariants(mesh: Mesh, V: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(n, q) rigid invariants of every vertex: distance from ``c``, then its star's edge lengths
    sorted (padded with -1 to the largest valence)."""
    t = mesh.topology
    E = t.edges
    L = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    ends = np.concatenate([E[:, 0], E[:, 1]])
    lens = np.concatenate([L, L])
    order = np.lexsort((-lens, ends))
    ends, lens = ends[order], lens[order]
    n = len(V)
    count = np.bincount(ends, minlength=n)
    k = int(count.max(initial=0))
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    slot = np.arange(len(ends)) - start[ends]
    star = np.full((n, k), -1.0)
    star[ends, slot] = lens
    return np.concatenate([np.linalg.norm(V - c, axis=1)[:, None], star], axis=1)


def _frame(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(3, 3) orthonormal columns from ``p`` and the part of ``q`` orthogonal to it."""
    u = p / np.linalg.norm(p)
    w = q - (q @ u) * u
    w = w / np.linalg.norm(w)
    return np.stack([u, w, np.cross(u, w)], axis=1)


def detect(mesh: Mesh, tol: float = TOLERANCE) -> Group:
    """The rigid symmetries of ``mesh`` within ``tol`` x its bounding-box diagonal (module text).

    Returns a :class:`Group` (the identity alone when there are none)."""
    from scipy.spatial import cKDTree

    V = np.asarray(mesh.V, dtype=float)
    n = len(V)
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0))) if n else 0.0
    atol = tol * diag
    if n < 3 or diag == 0.0:
        return trivial(mesh)
    c = V.mean(axis=0)
    inv = _invariants(mesh, V, c)
    tree = cKDTree(inv)
    radius = 4.0 * atol
    # anchors: far from the centre (well-conditioned frames), with the rarest invariants
    r = inv[:, 0]
    far = np.nonzero(r > 0.25 * r.max())[0]
    same = np.array([len(s) for s in tree.query_ball_point(inv[far], radius, p=np.inf)])
    a = int(far[np.lexsort((far, same))[0]])
    da = V - c
    cosang = (da @ da[a]) / np.maximum(np.linalg.norm(da, axis=1) * np.linalg.norm(da[a]), 1e-300)
    ok = far[np.abs(cosang[far]) < 0.9]
    if not len(ok):
        ok = np.nonzero((np.abs(cosang) < 0.999) & (r > 1e-6 * r.max()))[0]
    if not len(ok):
        return trivial(mesh)
    same_b = np.array([len(s) for s in tree.query_ball_point(inv[ok], radius, p=np.inf)])
    b = int(ok[np.lexsort((ok, same_b))[0]])
    A_img = np.asarray(tree.query_ball_point(inv[a], radius, p=np.inf), dtype=np.int64)
    B_img = np.asarray(tree.query_ball_point(inv[b], radius, p=np.inf), dtype=np.int64)
    dab = np.linalg.norm(V[a] - V[b])
    pairs = [(i, j) for i in A_img.tolist() for j in B_img.tolist()
             if i != j and abs(np.linalg.norm(V[i] - V[j]) - dab) <= 4.0 * atol]
    pairs = pairs[:MAX_CANDIDATES]
    Fa = _frame(da[a], da[b])
    vtree = cKDTree(V)
    F = mesh.F
    found: dict[bytes, Symmetry] = {}
    sample = np.unique(np.linspace(0, n - 1, min(n, 64)).astype(np.int64))
    for i, j in pairs:
        Fi = _frame(da[i], da[j])
        for hand in (1.0, -1.0):
            R = Fi @ np.diag([1.0, 1.0, hand]) @ Fa.T
            d_s, _ = vtree.query(da[sample] @ R.T + c, distance_upper_bound=max(atol, 1e-300) * 10)
            if not np.all(d_s <= atol):  # most candidates fail on a few vertices
                continue
            X = da @ R.T + c
            dist, perm = vtree.query(X, distance_upper_bound=max(atol, 1e-300) * 10)
            if not np.all(dist <= atol) or len(np.unique(perm)) != n:
                continue
            key = perm.astype(np.int64).tobytes()
            if key in found:
                continue
            fmap = _face_map(F, perm.astype(np.int64))
            if fmap is None:
                continue
            R, t = _refit(V, perm)
            found[key] = Symmetry(R, t, perm.astype(np.int64), fmap)
    ident = np.arange(n).tobytes()
    maps = [found.pop(ident)] if ident in found else list(trivial(mesh).maps)
    maps += sorted(found.values(), key=lambda g: g.perm.tolist())
    return Group(tuple(maps), atol)


def _refit(V: np.ndarray, perm: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The orthogonal ``R`` and ``t`` best mapping ``V`` onto ``V[perm]`` (Kabsch with reflections
    allowed: the rotation or reflection the permutation describes)."""
    c = V.mean(axis=0)
    X, Y = V - c, V[perm] - c
    U, _, Wt = np.linalg.svd(X.T @ Y)
    R = (U @ Wt).T
    return R, c - R @ c
