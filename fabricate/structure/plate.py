"""A simply supported plate under uniform pressure, any convex outline: deflection, moments, volume.

Kirchhoff plate theory, linear (small deflections; membrane action, which
relieves a glass pane once its deflection passes about its thickness, is left
out: conservative for stress and deflection).  Every edge is a straight line
support (``w = 0``, free to rotate): a glass panel bearing on the beams on all
its sides.  Then ``D lap^2 w = q`` splits into two Poisson problems with zero
boundary values (on straight simply supported edges ``w = 0`` and ``M_n = 0``
give ``lap w = 0``, Timoshenko & Woinowsky-Krieger, Theory of plates and shells,
section 29):

    - lap m = q,   m = 0 on the edge       (m = (M_x + M_y) / (1 + nu), the moment sum)
    - lap w = m / D,  w = 0 on the edge

both solved with linear triangles on one mesh (one factorization).  The moment
sum comes straight from the first solve; the principal moments need the
curvature difference and the twist as well, recovered from ``w`` by averaging
the element gradients to the nodes twice (gradient recovery), and combined with
the moment sum of the first solve.

For ``q = 1`` and ``D = 1`` the solution is the plate's *unit response*
(:class:`PlateResponse`); a pane of stiffness ``D`` under ``q`` deflects
``q / D`` times as much and carries ``q`` times the moments (a simply supported
plate's moments do not depend on ``D``), so one solve serves every load and
build-up of one outline.  Checked against Navier's series for rectangles and
the closed form of the equilateral triangle (tests/test_glass_check.py).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from optimize.errors import MeshError

RINGS = 24
"""Default mesh density: pieces per side of each fan triangle (a ``k``-gon gets ``(k - 2) RINGS^2`` triangles)."""


@dataclass(frozen=True)
class PlateResponse:
    """The unit response (``q = 1``, ``D = 1``) of a simply supported plate of one outline, mm.

    w_max : largest deflection (mm^4: times ``q / D`` gives mm, ``q`` in N/mm2, ``D`` in N mm).
    m_max : largest principal bending moment magnitude (mm^2: times ``q`` gives N mm/mm); ``6 q m_max / h^2``
        is the largest surface stress of a pane ``h`` thick.
    volume : the volume swept by the deflection (mm^6: times ``q / D`` gives mm^3).
    area : the outline's area (mm2).  inradius : radius of its largest inscribed circle (mm).
    nu : Poisson's ratio the moments were computed for.
    """

    w_max: float
    m_max: float
    volume: float
    area: float
    inradius: float
    nu: float


@lru_cache(maxsize=32)
def polygon_mesh(k: int, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Connectivity of a convex ``k``-gon's mesh (topology only, cached): the fan of triangles
    ``(0, j, j + 1)`` from corner 0, each cut in ``n^2`` by lines parallel to its sides (a rectangle
    becomes a regular ``n x n`` grid of cells split along one diagonal, a triangle its regular
    subdivision: meshes on which averaged gradients are accurate to second order).

    Returns ``W (N, k)`` float: each node as weights of the corners, ``T ((k - 2) n^2, 3)`` int
    triangles (counter-clockwise for a counter-clockwise outline), ``edge (N,)`` bool: nodes on the
    outline."""
    if k < 3 or n < 1:
        raise ValueError(f"polygon_mesh: k = {k}, n = {n}: expected k >= 3 corners and n >= 1")
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    keep = i + j <= n
    i, j = i[keep], j[keep]                                       # barycentric grid of one triangle
    local = -np.ones((n + 1, n + 1), dtype=np.int64)
    local[i, j] = np.arange(len(i))
    a, b = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    up = a + b <= n - 1
    a2, b2 = a[a + b <= n - 2], b[a + b <= n - 2]
    tri = np.concatenate([np.stack([local[a[up], b[up]], local[a[up] + 1, b[up]], local[a[up], b[up] + 1]], -1),
                          np.stack([local[a2 + 1, b2], local[a2 + 1, b2 + 1], local[a2, b2 + 1]], -1)])
    weights, tris = [], []
    for t in range(k - 2):  # k - 2 triangles of the fan, each a whole array
        w = np.zeros((len(i), k), dtype=np.int64)
        w[:, 0], w[:, t + 1], w[:, t + 2] = n - i - j, i, j
        tris.append(tri + t * len(i))
        weights.append(w)
    Wint, inverse = np.unique(np.concatenate(weights), axis=0, return_inverse=True)
    T = inverse.ravel()[np.concatenate(tris)]
    nz = Wint > 0
    support = nz.sum(axis=1)
    first = np.argmax(nz, axis=1)
    last = k - 1 - np.argmax(nz[:, ::-1], axis=1)
    edge = (support == 1) | ((support == 2) & ((last - first == 1) | ((first == 0) & (last == k - 1))))
    return Wint / n, T.astype(np.int64), edge


def _gradients(X: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(G (t, 3, 2), area (t,))``: gradients of the three hat functions of each triangle."""
    P = X[T]
    e1, e2 = P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    inv = np.stack([np.stack([e2[:, 1], -e1[:, 1]], -1), np.stack([-e2[:, 0], e1[:, 0]], -1)], -2) / det[:, None, None]
    ref = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
    G = np.einsum("aj,tij->tai", ref, inv)                      # d phi_a / d x_i
    return G, 0.5 * det


def _recover(values: np.ndarray, G: np.ndarray, T: np.ndarray, area: np.ndarray, n: int) -> np.ndarray:
    """(N, 2 ...) nodal gradients of nodal ``values (N, ...)``: element gradients averaged by area."""
    g = np.einsum("tai,ta...->t...i", G, values[T])
    out = np.zeros((n,) + g.shape[1:])
    np.add.at(out, T.ravel(), np.repeat(g * area.reshape((-1,) + (1,) * (g.ndim - 1)), 3, axis=0))
    weight = np.bincount(T.ravel(), weights=np.repeat(area, 3), minlength=n)
    return out / weight.reshape((-1,) + (1,) * (g.ndim - 1))


def inradius(outline: np.ndarray) -> float:
    """Radius of the largest circle inside a convex ``outline (k, 2)`` (mm): a small linear program."""
    from scipy.optimize import linprog

    P = np.asarray(outline, float)
    d = np.roll(P, -1, axis=0) - P
    L = np.linalg.norm(d, axis=1)
    normal = np.stack([d[:, 1], -d[:, 0]], axis=1) / L[:, None]          # outward for a CCW outline
    # maximize r subject to normal . x + r <= normal . P
    res = linprog([0.0, 0.0, -1.0], A_ub=np.column_stack([normal, np.ones(len(P))]),
                  b_ub=np.einsum("ki,ki->k", normal, P), bounds=[(None, None), (None, None), (0, None)])
    return float(res.x[2]) if res.status == 0 else 0.0


def solve_plate(outline: np.ndarray, nu: float, rings: int = RINGS) -> PlateResponse:
    """The unit response of the simply supported plate on the convex ``outline (k, 2)`` (mm, any order).

    Raises MeshError for an outline that is not a convex polygon of positive area."""
    P = np.asarray(outline, dtype=float)
    if P.ndim != 2 or P.shape[1] != 2 or len(P) < 3 or not np.isfinite(P).all():
        raise MeshError(f"plate outline of shape {P.shape}: expected (k, 2) finite corners, k >= 3")
    d = np.roll(P, -1, axis=0) - P
    cross = d[:, 0] * np.roll(d, -1, axis=0)[:, 1] - d[:, 1] * np.roll(d, -1, axis=0)[:, 0]
    if cross.sum() < 0:
        P, cross = P[::-1], -cross
    if cross.sum() <= 0 or (cross < -1e-9 * np.abs(cross).max()).any():
        raise MeshError(f"plate outline {np.round(P, 1).tolist()}: expected a convex polygon of positive area")
    P0 = P - P.mean(axis=0)                                       # about the corner mean: no round-off far out
    Q = np.roll(P0, -1, axis=0)
    area2 = P0[:, 0] * Q[:, 1] - P0[:, 1] * Q[:, 0]
    w_max, m_max, volume = _solve(P0, nu, rings)
    if rings >= 8 and rings % 2 == 0:  # Richardson: the errors fall as h^2 (tests/test_glass_check.py)
        w_max, m_max, volume = (4.0 * np.array([w_max, m_max, volume]) - _solve(P0, nu, rings // 2)) / 3.0
    return PlateResponse(w_max=float(w_max), m_max=float(m_max), volume=float(volume), area=float(0.5 * area2.sum()),
                         inradius=inradius(P), nu=float(nu))


def _solve(P0: np.ndarray, nu: float, n: int) -> np.ndarray:
    """``[w_max, m_max, volume]`` of the unit response on the mesh of ``n`` pieces per side of the
    counter-clockwise convex ``P0 (k, 2)``."""
    import scipy.sparse as sp                                     # light to import: the config reads GlassOptions
    from scipy.sparse.linalg import splu

    W, T, edge = polygon_mesh(len(P0), n)
    X = W @ P0
    G, area = _gradients(X, T)
    N = len(X)
    rows, cols = np.repeat(T, 3, axis=1).ravel(), np.tile(T, (1, 3)).ravel()
    K = sp.coo_matrix((np.einsum("tai,tbi->tab", G, G).ravel() * np.repeat(area, 9), (rows, cols)),
                      shape=(N, N)).tocsc()
    local = (np.ones((3, 3)) + np.eye(3)) / 12.0
    M = sp.coo_matrix(((area[:, None, None] * local).ravel(), (rows, cols)), shape=(N, N)).tocsr()
    inner = np.flatnonzero(~edge)
    lu = splu(K[inner][:, inner].tocsc())
    m = np.zeros(N)
    m[inner] = lu.solve(np.asarray(M[inner].sum(axis=1)).ravel())
    w = np.zeros(N)
    w[inner] = lu.solve(M[inner] @ m)
    grad = _recover(w, G, T, area, N)                             # (N, 2)
    H = _recover(grad, G, T, area, N)                             # (N, 2, 2): H[:, i, j] = d_j (d_i w)
    wxx, wyy, wxy = H[:, 0, 0], H[:, 1, 1], 0.5 * (H[:, 0, 1] + H[:, 1, 0])
    centre = 0.5 * (1.0 + nu) * m                                 # (M1 + M2) / 2, from the first solve
    radius = (1.0 - nu) * np.hypot(0.5 * (wxx - wyy), wxy)        # (M1 - M2) / 2, recovered
    return np.array([w.max(), (np.abs(centre) + radius).max(), np.asarray(M.sum(axis=0)).ravel() @ w])
