"""Principal directions of a triangulated surface by integral invariants (paper section 5).

At a point ``p`` of the surface let ``D = B_r(p) ∩ Inside``.  The covariance
matrix of ``D`` about its barycentre has one eigenvector close to the surface
normal and two in the tangent plane along the principal directions; its
tangent eigenvalues are (Pottmann, Wallner, Yang, Lai, Hu 2007, "Principal
curvatures from the integral invariant viewpoint")::

    M1 = 2 pi r^5 / 15 - pi (3 k1 + k2) r^6 / 48 + O(r^7)
    M2 = 2 pi r^5 / 15 - pi (k1 + 3 k2) r^6 / 48 + O(r^7)

(``k`` positive where the surface bends away from the outward normal, like a
sphere seen from outside), so ``k1 = 6 (M2 - 3 M1) / (pi r^6) + 8 / (5 r)``.
Being volume integrals these are insensitive to noise of the triangle mesh
well below ``r`` (the point of the method).

What is inside.  A closed surface bounds its inside.  For an open surface (a
roof, a facade) the user names the side that plays the inside with a vector
``side`` (default ``(0, 0, -1)``: below the roof); faces are oriented so their
normals point away from it.

How the volume integrals are computed (exact along lines, a lattice sum
across them).  For each point ``p`` a hexagonal lattice of lines parallel to
the vertex normal ``n_p`` with spacing ``h = r / resolution`` is laid in the
tangent plane.  Every lattice line meets the ball in a chord ``[-a, a]``.  The
line's crossings with the triangles near ``p`` (a vectorized point-in-triangle
test in ``p``'s frame, with the top-left rule so that a line through a shared
vertex or edge counts once) split it into intervals; the orientation of each
crossing (in or out) says which intervals are inside.  The integrals of
``1, t, t^2`` over the inside part of the chord are then exact, and the lattice
sum over lines (weight: the hexagonal cell area) does the two remaining
dimensions.  A hexagonal lattice is 6-fold symmetric, so its moment tensors
are isotropic up to fourth order: the quadrature introduces no preferred
direction.  The curvature offset ``8 / (5 r)`` is replaced by the value the
same quadrature gives for a plane, so a plane has zero estimated curvature.

A line that meets no triangle near ``p`` (beyond the boundary of an open
surface) is split by ``p``'s tangent plane: the surface is extended by its
tangent plane across the boundary.  Within ``r`` of the boundary this keeps
the estimate defined but biases curvature toward zero.

The classical estimate (a local quadric fit, for comparison) is in
:mod:`optimize.remesh.principal_quadric`.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..errors import ConfigError, MeshError
from ..mesh import Mesh

log = logging.getLogger(__name__)

DEFAULT_SIDE = (0.0, 0.0, -1.0)
_GENERIC = np.array([0.2718281828, 0.5772156649, 0.7071067812])  # frame seed, never axis-aligned


@dataclass(frozen=True)
class PrincipalFrames:
    """Principal frames at ``k`` points of a surface (world coordinates).

    k1dir, k2dir : (k, 3) unit tangent vectors; ``k1`` is the larger curvature.
    normals : (k, 3) unit outward vertex normals (area weighted); ``k2dir =
        normals x k1dir``.
    k1, k2 : (k,) principal curvature estimates, positive where the surface
        bends away from its outward normal.
    pca_normals : (k, 3) the covariance eigenvector along the normal (volume
        PCA only; the quadric fit gives its own fitted normal).
    radius : the kernel radius used.
    """

    k1dir: np.ndarray
    k2dir: np.ndarray
    normals: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    pca_normals: np.ndarray
    radius: float

    @property
    def anisotropy(self) -> np.ndarray:
        """(k,) ``(k1 - k2) r``: how well the directions are defined (0 at umbilics)."""
        return (self.k1 - self.k2) * self.radius


# -- the surface: orientation and normals -------------------------------------
def oriented_surface(V, T, side=None, name: str = "surface") -> tuple[Mesh, np.ndarray, bool]:
    """Orient a triangle mesh so its normals point away from the inside.

    V : (n, 3) float, T : (t, 3) int.  side : (3,) vector toward the inside of an
    open surface (default ``(0, 0, -1)``), or ``"keep"``: the faces' own
    orientation (their normals point outside; for a tube or a tunnel, where no
    one direction points inside everywhere); ignored for a closed surface.
    Returns ``(mesh, normals (n, 3) unit area-weighted vertex normals, closed)``.
    Raises MeshError (non-triangles, non-orientable) and ConfigError (a side
    vector that does not tell the two sides apart).
    """
    mesh = V if isinstance(V, Mesh) else Mesh(V, T, name=name)
    if mesh.F.shape[1] != 3 or np.any(mesh.F < 0):
        raise MeshError(f"{mesh.name}: expected a triangle mesh, found faces of up to "
                        f"{mesh.F.shape[1]} vertices (triangulate it first)")
    if not mesh.topology.orientable:
        raise MeshError(f"{mesh.name}: the surface is not orientable, expected two sides")
    F, P = mesh.F, mesh.V
    closed = not bool(mesh.topology.is_boundary_edge.any())
    fn = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])  # 2 x area-weighted
    comp = mesh.topology.component[F[:, 0]]
    if closed:
        score = np.bincount(comp, np.einsum("ij,ij->i", fn, P[F[:, 0]]))  # 6 x signed volume
    elif isinstance(side, str) and side == "keep":  # the file's orientation: normals point outside
        score = np.ones(comp.max() + 1)
    else:
        s = _unit_side(side)
        score = -np.bincount(comp, fn @ s)
        total = np.bincount(comp, np.linalg.norm(fn, axis=1))
        weak = np.abs(score) < 0.05 * total
        if weak.any():
            raise ConfigError(f"{mesh.name}: side vector {s.round(4).tolist()} does not tell the two "
                              f"sides of the surface apart (mean normal nearly perpendicular to it); "
                              f"expected a vector pointing to the inside (for a facade: horizontal, into the building)")
    flip = score[comp] < 0
    if flip.any():
        F = np.where(flip[:, None], F[:, ::-1], F)
        fn = np.where(flip[:, None], -fn, fn)
        mesh = Mesh(mesh.V, F, name=mesh.name)
    N = np.zeros_like(P)
    for j in range(3):
        N += np.stack([np.bincount(F[:, j], fn[:, c], minlength=len(P)) for c in range(3)], axis=1)
    N /= np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    return mesh, N, closed


def _unit_side(side) -> np.ndarray:
    if isinstance(side, str):
        raise ConfigError(f"side = {side!r}, expected a nonzero 3-vector x,y,z or 'keep'")
    s = np.asarray(DEFAULT_SIDE if side is None else side, dtype=float).reshape(-1)
    if s.shape != (3,) or not np.all(np.isfinite(s)) or np.linalg.norm(s) == 0:
        raise ConfigError(f"side = {np.asarray(side).tolist()}, expected a nonzero 3-vector x,y,z")
    return s / np.linalg.norm(s)


def tangent_frames(N: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(k, 3), (k, 3): unit vectors ``e1, e2`` completing unit normals ``N (k, 3)`` to right-handed frames."""
    g = np.broadcast_to(_GENERIC / np.linalg.norm(_GENERIC), N.shape)
    alt = np.broadcast_to(np.array([1.0, 0.0, 0.0]), N.shape)
    g = np.where((np.abs(np.einsum("ij,ij->i", N, g)) > 0.99)[:, None], alt, g)
    e1 = np.cross(g, N)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return e1, np.cross(N, e1)


def vertex_indices(at, n: int) -> np.ndarray:
    """(k,) int64 vertex indices ``at`` (all ``n`` when None); ConfigError when one is out of range."""
    if at is None:
        return np.arange(n)
    idx = np.asarray(at, dtype=np.int64).reshape(-1)
    bad = (idx < 0) | (idx >= n)
    if bad.any():
        raise ConfigError(f"at: vertex index {int(idx[bad][0])} is out of range, expected 0..{n - 1}")
    return idx


def _check(radius: float, resolution: int) -> None:
    if not np.isfinite(radius) or radius <= 0:
        raise ConfigError(f"radius = {radius}, expected a positive length")
    if int(resolution) < 2:
        raise ConfigError(f"resolution = {resolution}, expected at least 2 lattice lines per radius")


# -- the lattice of lines -----------------------------------------------------
class _Lattice:
    """Hexagonal lattice of lines in the tangent plane, spacing ``h = r / resolution``."""

    def __init__(self, radius: float, resolution: int):
        self.r = float(radius)
        self.h = self.r / resolution
        self.S = int(np.ceil(2 * resolution / np.sqrt(3))) + 2
        s, t = np.meshgrid(np.arange(-self.S, self.S + 1), np.arange(-self.S, self.S + 1), indexing="ij")
        x, y = self.to_xy(s.ravel(), t.ravel())
        keep = x * x + y * y < self.r ** 2
        self.lut = np.full(s.size, -1, dtype=np.int64)
        self.lut[keep] = np.arange(keep.sum())
        self.x, self.y = x[keep], y[keep]  # (C,)
        self.a = np.sqrt(self.r ** 2 - self.x ** 2 - self.y ** 2)  # (C,) chord half-lengths
        self.w = self.h ** 2 * np.sqrt(3) / 2  # cell area

    def to_xy(self, s, t):
        return self.h * (s + 0.5 * t), self.h * (np.sqrt(3) / 2) * t

    def to_st(self, x, y):
        t = y / (self.h * np.sqrt(3) / 2)
        return x / self.h - 0.5 * t, t

    @property
    def n_columns(self) -> int:
        return len(self.x)


def _interval_moments(lo, hi, a):
    """Integrals of 1, t, t^2 over ``[lo, hi] ∩ [-a, a]`` (arrays of one shape)."""
    lo = np.maximum(lo, -a)
    hi = np.minimum(hi, a)
    ok = hi > lo
    lo, hi = np.where(ok, lo, 0.0), np.where(ok, hi, 0.0)
    return hi - lo, (hi ** 2 - lo ** 2) / 2, (hi ** 3 - lo ** 3) / 3


def _column_moments(P, Nf, E1, E2, tri_xyz, pairs, lat: _Lattice):
    """Chord moments ``L (k, C, 3)`` (integrals of 1, t, t^2 of the inside part of every chord).

    P, Nf, E1, E2 : (k, 3) points and frames; tri_xyz : (t, 3, 3) triangles;
    pairs : (q, 2) (point, triangle) candidates.
    """
    k, C = len(P), lat.n_columns
    # default: the tangent plane splits the chord, inside below (t < 0)
    L = np.stack(_interval_moments(np.full(C, -np.inf), np.zeros(C), lat.a), axis=1)
    L = np.broadcast_to(L, (k, C, 3)).copy()
    if len(pairs) == 0:
        return L
    pi, ti = pairs[:, 0], pairs[:, 1]
    R = np.stack([E1[pi], E2[pi], Nf[pi]], axis=1)  # (q, 3, 3) rows: frame
    X = np.einsum("qab,qcb->qca", R, tri_xyz[ti] - P[pi][:, None, :])  # (q, 3 verts, 3)
    area2 = ((X[:, 1, 0] - X[:, 0, 0]) * (X[:, 2, 1] - X[:, 0, 1])
             - (X[:, 1, 1] - X[:, 0, 1]) * (X[:, 2, 0] - X[:, 0, 0]))
    scale = np.abs(X[:, :, :2]).max(axis=(1, 2)) + lat.h
    gap = np.maximum(np.maximum(X[:, :, :2].min(1), -X[:, :, :2].max(1)), 0.0)  # (q, 2) bbox to origin
    good = (np.abs(area2) > 1e-12 * scale ** 2) & (np.einsum("ij,ij->i", gap, gap) < lat.r ** 2)
    pi, X, area2 = pi[good], X[good], area2[good]
    sigma = np.sign(area2)  # +1: the triangle faces along +n (the line leaves the inside)
    X = np.where((sigma < 0)[:, None, None], X[:, [0, 2, 1]], X)  # make every triangle CCW in 2D
    s, t = lat.to_st(X[:, :, 0], X[:, :, 1])
    s0 = np.maximum(np.ceil(s.min(1)), -lat.S).astype(np.int64)
    s1 = np.minimum(np.floor(s.max(1)), lat.S).astype(np.int64)
    t0 = np.maximum(np.ceil(t.min(1)), -lat.S).astype(np.int64)
    t1 = np.minimum(np.floor(t.max(1)), lat.S).astype(np.int64)
    ns, nt = np.maximum(s1 - s0 + 1, 0), np.maximum(t1 - t0 + 1, 0)
    cnt = ns * nt
    q = np.repeat(np.arange(len(pi)), cnt)
    loc = np.arange(len(q)) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    ls, lt = s0[q] + loc // nt[q], t0[q] + loc % nt[q]
    col = lat.lut[(ls + lat.S) * (2 * lat.S + 1) + (lt + lat.S)]
    sel = col >= 0
    q, ls, lt, col = q[sel], ls[sel], lt[sel], col[sel]
    qx, qy = lat.x[col], lat.y[col]
    Xq = X[q]
    inside = np.ones(len(q), dtype=bool)
    bary = []
    for j in range(3):  # the three edge functions, top-left rule on ties
        x0, y0 = Xq[:, j, 0], Xq[:, j, 1]
        dx, dy = Xq[:, (j + 1) % 3, 0] - x0, Xq[:, (j + 1) % 3, 1] - y0
        e = dx * (qy - y0) - dy * (qx - x0)
        inside &= (e > 0) | ((e == 0) & ((dy < 0) | ((dy == 0) & (dx < 0))))
        bary.append(e)
    q, col = q[inside], col[inside]
    b = np.stack([bary[1][inside], bary[2][inside], bary[0][inside]], axis=1)  # opposite-vertex weights
    b /= b.sum(axis=1, keepdims=True)
    z = np.einsum("ij,ij->i", b, X[q][:, :, 2])
    sg = sigma[q]
    # sort crossings per (point, column) by height; intervals between them
    gid = pi[q] * C + col
    order = np.lexsort((z, gid))
    gid, z, sg = gid[order], z[order], sg[order]
    last = np.append(gid[1:] != gid[:-1], True)
    first = np.insert(gid[1:] != gid[:-1], 0, True)
    znext = np.where(last, np.inf, np.append(z[1:], np.inf))
    a = lat.a[gid % C]
    after = _interval_moments(z, znext, a)  # inside when entering (sigma < 0)
    before = _interval_moments(np.full_like(z, -np.inf), z, a)  # inside when the first one leaves
    Lg = np.zeros((k * C, 3))
    hit = np.zeros(k * C, dtype=bool)
    hit[gid] = True
    for m in range(3):
        val = np.where(sg < 0, after[m], 0.0) + np.where(first & (sg > 0), before[m], 0.0)
        Lg[:, m] = np.bincount(gid, val, minlength=k * C)
    L = L.reshape(k * C, 3)
    L[hit] = Lg[hit]
    return L.reshape(k, C, 3)


def _covariance(L: np.ndarray, lat: _Lattice) -> np.ndarray:
    """(k, 3, 3) covariance about the barycentre (not divided by the volume), local frame."""
    x, y, w = lat.x, lat.y, lat.w
    L0, L1, L2 = L[..., 0], L[..., 1], L[..., 2]
    M0 = w * L0.sum(1)
    m = w * np.stack([L0 @ x, L0 @ y, L1.sum(1)], axis=1) / M0[:, None]
    S = np.empty((len(L), 3, 3))
    S[:, 0, 0] = w * (L0 @ (x * x))
    S[:, 1, 1] = w * (L0 @ (y * y))
    S[:, 2, 2] = w * L2.sum(1)
    S[:, 0, 1] = S[:, 1, 0] = w * (L0 @ (x * y))
    S[:, 0, 2] = S[:, 2, 0] = w * (L1 @ x)
    S[:, 1, 2] = S[:, 2, 1] = w * (L1 @ y)
    return S - M0[:, None, None] * np.einsum("ki,kj->kij", m, m)


def principal_frames(V, T=None, radius: float = 1.0, *, side=None, at=None, resolution: int = 8,
                     chunk: int = 256) -> PrincipalFrames:
    """Principal frames by volume PCA of ``B_r(p) ∩ Inside`` (integral invariants).

    V : (n, 3) float or a triangle :class:`Mesh`; T : (t, 3) int (None with a Mesh).
    radius : kernel radius ``r`` (model units); choose it about the size of
        the details to ignore (noise, faceting) and below the size of the
        features to follow.
    side : (3,) vector pointing to the inside of an open surface (default
        ``(0, 0, -1)``); ignored for a closed surface.
    at : (k,) int vertex indices to evaluate at (default: every vertex).
    resolution : lattice lines per radius (``h = r / resolution``).
    Returns :class:`PrincipalFrames` with ``(k, ...)`` arrays.
    """
    _check(radius, resolution)
    mesh, N, _ = oriented_surface(V, T, side)
    at = vertex_indices(at, mesh.n_vertices)
    lat = _Lattice(radius, int(resolution))
    tri = mesh.V[mesh.F]  # (t, 3, 3)
    cen = tri.mean(axis=1)
    reach = 1.5 * radius + np.linalg.norm(tri - cen[:, None], axis=2).max()
    ctree = cKDTree(cen)
    P, Np = mesh.V[at], N[at]
    E1, E2 = tangent_frames(Np)
    Cov = np.empty((len(at), 3, 3))
    for s in range(0, len(at), chunk):  # chunks bound the memory, each is vectorized
        sl = slice(s, s + chunk)
        pairs = cKDTree(P[sl]).sparse_distance_matrix(ctree, reach, output_type="ndarray")
        pairs = np.stack([pairs["i"], pairs["j"]], axis=1).astype(np.int64)
        L = _column_moments(P[sl], Np[sl], E1[sl], E2[sl], tri, pairs, lat)
        Cov[sl] = _covariance(L, lat)
    flat = _covariance(np.stack(_interval_moments(np.full(lat.n_columns, -np.inf),
                                                  np.zeros(lat.n_columns), lat.a), axis=1)[None], lat)[0]
    lam_flat = 0.5 * (flat[0, 0] + flat[1, 1])
    return _frames_from_covariance(Cov, lam_flat, E1, E2, Np, radius)


def _frames_from_covariance(Cov, lam_flat, E1, E2, Np, radius) -> PrincipalFrames:
    lam, vec = np.linalg.eigh(Cov)  # ascending; columns are eigenvectors (local frame)
    inormal = np.argmax(np.abs(vec[:, 2, :]), axis=1)
    k = len(Cov)
    idx = np.array([[1, 2], [0, 2], [0, 1]])[inormal]  # the two tangent eigenvectors, ascending
    rows = np.arange(k)
    v_small = vec[rows, :, idx[:, 0]]
    m1, m2 = lam[rows, idx[:, 0]], lam[rows, idx[:, 1]]
    c = 6.0 / (np.pi * radius ** 6)
    k1 = c * (m2 - 3 * m1) + 2 * c * lam_flat
    k2 = c * (m1 - 3 * m2) + 2 * c * lam_flat
    d1 = v_small[:, :1] * E1 + v_small[:, 1:2] * E2  # projected onto the tangent plane of n_p
    d1 /= np.maximum(np.linalg.norm(d1, axis=1, keepdims=True), 1e-300)
    vn = vec[rows, :, inormal]
    pn = vn[:, :1] * E1 + vn[:, 1:2] * E2 + vn[:, 2:3] * Np
    pn *= np.sign(vn[:, 2:3] + (vn[:, 2:3] == 0))
    return PrincipalFrames(k1dir=d1, k2dir=np.cross(Np, d1), normals=Np.copy(), k1=k1, k2=k2,
                           pca_normals=pn, radius=float(radius))


def principal_directions(V, T, radius: float, *, side=None, at=None, resolution: int = 8):
    """Principal directions by volume PCA (see :func:`principal_frames`).

    V : (n, 3) float, T : (t, 3) int.  Returns ``(k1dir (k, 3), k2dir (k, 3),
    normals (k, 3))`` unit vectors at the vertices ``at`` (default all).
    """
    fr = principal_frames(V, T, radius, side=side, at=at, resolution=resolution)
    return fr.k1dir, fr.k2dir, fr.normals
