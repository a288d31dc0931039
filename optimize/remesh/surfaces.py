"""Triangulated analytic surfaces with exact principal directions.

The inputs of the remeshing stage in tests and benchmarks: an ellipsoid and a
torus (closed), a patch of a surface of revolution and height fields (open,
disk-like, like roofs).  Each comes with its implicit function ``F`` (outside
where ``F > 0``), whose gradient and Hessian give the exact shape operator
``S = P H P / |grad F|`` (``P`` the tangent projector): its tangent
eigenvectors are the principal directions, its eigenvalues the curvatures
(positive where the surface bends away from the outward normal).

Triangulations are irregular on purpose (jittered points, Delaunay in the
parameter domain), seeded, so that no mesh edge runs along a principal line by
construction.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.spatial import Delaunay

from ..mesh import Mesh


@dataclass(frozen=True)
class AnalyticSurface:
    """A triangle mesh sampled from an implicit surface, with exact differential geometry.

    mesh : triangle Mesh, vertices on the surface.
    grad, hess : ``P (k, 3) -> (k, 3)`` and ``-> (k, 3, 3)`` of ``F`` (outside ``F > 0``).
    side : (3,) vector toward the inside for an open surface (None when closed).
    """

    mesh: Mesh
    grad: Callable[[np.ndarray], np.ndarray]
    hess: Callable[[np.ndarray], np.ndarray]
    side: tuple | None = None

    def exact(self, P: np.ndarray | None = None):
        """Exact ``(k1dir, k2dir, normals (k, 3), k1, k2 (k,))`` at points ``P (k, 3)`` (default: vertices)."""
        P = self.mesh.V if P is None else np.asarray(P, dtype=float)
        g = self.grad(P)
        gn = np.linalg.norm(g, axis=1)
        n = g / gn[:, None]
        Pr = np.eye(3)[None] - np.einsum("ki,kj->kij", n, n)
        S = np.einsum("kab,kbc,kcd->kad", Pr, self.hess(P), Pr) / gn[:, None, None]
        lam, vec = np.linalg.eigh(S)
        # the eigenvector along the normal has eigenvalue 0; drop it
        inormal = np.argmax(np.abs(np.einsum("kij,ki->kj", vec, n)), axis=1)
        idx = np.array([[1, 2], [0, 2], [0, 1]])[inormal]
        rows = np.arange(len(P))
        k2, k1 = lam[rows, idx[:, 0]], lam[rows, idx[:, 1]]
        d1 = vec[rows, :, idx[:, 1]]
        return d1, np.cross(n, d1), n, k1, k2


def _icosphere(level: int) -> tuple[np.ndarray, np.ndarray]:
    t = (1 + 5 ** 0.5) / 2
    V = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
                  [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float)
    F = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                  [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
                  [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]])
    for _ in range(level):  # one vectorized midpoint split per level
        E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        uniq, inv = np.unique(E, axis=0, return_inverse=True)
        mid = len(V) + inv.reshape(3, -1).T  # (m, 3) midpoints of edges 01, 12, 20
        V = np.concatenate([V, 0.5 * (V[uniq[:, 0]] + V[uniq[:, 1]])])
        a, b, c = F.T
        ab, bc, ca = mid.T
        F = np.concatenate([np.stack(x, 1) for x in ([a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca])])
    return V / np.linalg.norm(V, axis=1, keepdims=True), F


def ellipsoid(a: float = 1.6, b: float = 1.2, c: float = 0.8, level: int = 4) -> AnalyticSurface:
    """Closed ellipsoid ``x^2/a^2 + y^2/b^2 + z^2/c^2 = 1`` from a subdivided icosahedron."""
    U, F = _icosphere(level)
    D = np.array([a, b, c], float)
    inv2 = 2.0 / D ** 2
    return AnalyticSurface(Mesh(U * D, F, name="ellipsoid"), grad=lambda P: P * inv2,
                           hess=lambda P: np.broadcast_to(np.diag(inv2), (len(P), 3, 3)).copy())


def _delaunay_patch(nu: int, nv: int, jitter: float, seed: int):
    """Jittered ``nu x nv`` points of ``[0, 1]^2`` (boundary points kept on the boundary) + Delaunay."""
    rng = np.random.default_rng(seed)
    u, v = np.meshgrid(np.linspace(0, 1, nu), np.linspace(0, 1, nv), indexing="ij")
    U = np.stack([u.ravel(), v.ravel()], 1)
    d = jitter * rng.uniform(-0.5, 0.5, U.shape) / np.array([nu - 1, nv - 1])
    edge = (np.isclose(U, 0) | np.isclose(U, 1))
    U = np.clip(np.where(edge, U, U + d), 0, 1)
    return U, Delaunay(U).simplices


def _torus_grid(nu: int, nv: int, jitter: float, seed: int):
    rng = np.random.default_rng(seed)
    i, j = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    U = np.stack([(i + jitter * rng.uniform(-0.5, 0.5, i.shape)).ravel() / nu,
                  (j + jitter * rng.uniform(-0.5, 0.5, j.shape)).ravel() / nv], 1)
    I, J = i.ravel(), j.ravel()
    a, b = I * nv + J, ((I + 1) % nu) * nv + J
    c, d = ((I + 1) % nu) * nv + (J + 1) % nv, I * nv + (J + 1) % nv
    flip = (I + J) % 2 == 0
    F = np.concatenate([np.where(flip[:, None], np.stack([a, b, c], 1), np.stack([a, b, d], 1)),
                        np.where(flip[:, None], np.stack([a, c, d], 1), np.stack([b, c, d], 1))])
    return U, F


def torus(R: float = 2.0, r: float = 0.7, nu: int = 90, nv: int = 36, jitter: float = 0.5,
          seed: int = 0) -> AnalyticSurface:
    """Closed torus about the z axis (tube radius ``r``), jittered grid triangulation."""
    U, F = _torus_grid(nu, nv, jitter, seed)
    th, ph = 2 * np.pi * U[:, 0], 2 * np.pi * U[:, 1]
    V = np.stack([(R + r * np.cos(ph)) * np.cos(th), (R + r * np.cos(ph)) * np.sin(th), r * np.sin(ph)], 1)

    def grad(P):
        rho = np.hypot(P[:, 0], P[:, 1])
        f = 2 * (rho - R) / rho
        return np.stack([f * P[:, 0], f * P[:, 1], 2 * P[:, 2]], 1)

    def hess(P):
        x, y = P[:, 0], P[:, 1]
        rho = np.hypot(x, y)
        H = np.zeros((len(P), 3, 3))
        H[:, 0, 0] = 2 - 2 * R * y * y / rho ** 3
        H[:, 1, 1] = 2 - 2 * R * x * x / rho ** 3
        H[:, 0, 1] = H[:, 1, 0] = 2 * R * x * y / rho ** 3
        H[:, 2, 2] = 2
        return H

    return AnalyticSurface(Mesh(V, F, name="torus"), grad=grad, hess=hess)


def revolution_patch(profile=None, theta: tuple = (0.0, np.pi / 2), z: tuple = (-1.0, 1.0),
                     n: tuple = (40, 30), jitter: float = 0.6, seed: int = 0) -> AnalyticSurface:
    """Disk-like patch of the surface of revolution ``rho = profile(z)`` about the z axis.

    profile : ``(rho(z), rho'(z), rho''(z))`` callables (default the waist
    ``1.5 + 0.25 z^2``: negatively curved, no umbilics).  Principal lines:
    meridians and parallels.  The inside is toward the axis (``side`` is the
    mean inward direction).
    """
    if profile is None:
        profile = (lambda z: 1.5 + 0.25 * z * z, lambda z: 0.5 * z, lambda z: np.full_like(z, 0.5))
    rho, drho, ddrho = profile
    U, F = _delaunay_patch(n[0], n[1], jitter, seed)
    th = theta[0] + (theta[1] - theta[0]) * U[:, 0]
    zz = z[0] + (z[1] - z[0]) * U[:, 1]
    V = np.stack([rho(zz) * np.cos(th), rho(zz) * np.sin(th), zz], 1)

    def grad(P):
        r = np.hypot(P[:, 0], P[:, 1])
        return np.stack([P[:, 0] / r, P[:, 1] / r, -drho(P[:, 2])], 1)

    def hess(P):
        x, y = P[:, 0], P[:, 1]
        r = np.hypot(x, y)
        H = np.zeros((len(P), 3, 3))
        H[:, 0, 0], H[:, 1, 1] = y * y / r ** 3, x * x / r ** 3
        H[:, 0, 1] = H[:, 1, 0] = -x * y / r ** 3
        H[:, 2, 2] = -ddrho(P[:, 2])
        return H

    tm = 0.5 * (theta[0] + theta[1])
    side = (-float(np.cos(tm)), -float(np.sin(tm)), 0.0)
    mesh = Mesh(V, F, name="revolution-patch")
    return AnalyticSurface(mesh, grad=grad, hess=hess, side=side)


def height_field(f=None, size: tuple = (4.0, 3.0), n: tuple = (41, 31), jitter: float = 0.6,
                 seed: int = 0, name: str = "roof") -> AnalyticSurface:
    """A roof ``z = f(x, y)`` over ``[-sx/2, sx/2] x [-sy/2, sy/2]``; the inside is below.

    f : ``(f, grad f (k, 2), hess f (k, 2, 2))`` callables of ``(x, y)`` arrays
    (default the saddle ``0.15 x^2 - 0.1 y^2 + 0.05 x y``).
    """
    if f is None:
        A = np.array([[0.3, 0.05], [0.05, -0.2]])
        f = (lambda x, y: 0.15 * x * x - 0.1 * y * y + 0.05 * x * y,
             lambda x, y: np.stack([0.3 * x + 0.05 * y, -0.2 * y + 0.05 * x], 1),
             lambda x, y: np.broadcast_to(A, (len(x), 2, 2)).copy())
    fun, dfun, ddfun = f
    U, F = _delaunay_patch(n[0], n[1], jitter, seed)
    x, y = (U[:, 0] - 0.5) * size[0], (U[:, 1] - 0.5) * size[1]
    V = np.stack([x, y, fun(x, y)], 1)

    def grad(P):  # F = z - f(x, y): outside (above) where F > 0
        g = dfun(P[:, 0], P[:, 1])
        return np.stack([-g[:, 0], -g[:, 1], np.ones(len(P))], 1)

    def hess(P):
        H = np.zeros((len(P), 3, 3))
        H[:, :2, :2] = -ddfun(P[:, 0], P[:, 1])
        return H

    return AnalyticSurface(Mesh(V, F, name=name), grad=grad, hess=hess, side=(0.0, 0.0, -1.0))


def holed_roof(radius: float = 0.6, centre: tuple = (0.3, 0.2), size: tuple = (4.0, 3.0), n: tuple = (41, 31),
               seed: int = 0, scale: float = 1.0, height=None, name: str = "holed-roof") -> Mesh:
    """A height field over a rectangle minus a disk: a roof with an opening (two boundary loops).

    radius, centre : the opening, in the roof's units before ``scale``; size : the
    rectangle (centred at the origin); n : grid points (jittered, Delaunay);
    height : ``z(x, y)`` on arrays (default the saddle ``0.15 x^2 - 0.1 y^2 + 0.05 x y``
    of :func:`height_field`); scale : multiplies every coordinate (6000 gives a
    24 m x 18 m roof in mm).  The rim of the opening is sampled exactly on the
    circle.  Returns the triangle Mesh.
    """
    if height is None:
        def height(x, y):
            return 0.15 * x ** 2 - 0.1 * y ** 2 + 0.05 * x * y
    rng = np.random.default_rng(seed)
    half = np.asarray(size, dtype=float) / 2
    x, y = np.meshgrid(np.linspace(-half[0], half[0], n[0]), np.linspace(-half[1], half[1], n[1]), indexing="ij")
    P = np.stack([x.ravel(), y.ravel()], 1)
    s = size[0] / (n[0] - 1)
    inner = np.all(np.abs(P) < half - 1e-9, axis=1)
    P[inner] += 0.3 * s * rng.uniform(-0.5, 0.5, (int(inner.sum()), 2))
    P = P[np.linalg.norm(P - centre, axis=1) > radius + 0.5 * s]
    k = int(np.ceil(2 * np.pi * radius / s))
    t = 2 * np.pi * np.arange(k) / k
    P = np.vstack([P, np.asarray(centre) + radius * np.stack([np.cos(t), np.sin(t)], 1)])
    T = Delaunay(P).simplices
    T = T[np.linalg.norm(P[T].mean(1) - centre, axis=1) > radius]
    return Mesh(scale * np.column_stack([P, height(P[:, 0], P[:, 1])]), T, name=name)


def angle_error(d: np.ndarray, d_exact: np.ndarray, n_exact: np.ndarray) -> np.ndarray:
    """(k,) degrees between line fields ``d`` and ``d_exact`` (k, 3) after projecting ``d`` on the exact tangent plane."""
    d = d - np.einsum("ij,ij->i", d, n_exact)[:, None] * n_exact
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    return np.degrees(np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", d, d_exact)), 0, 1)))
