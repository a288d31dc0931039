"""The classical principal-direction estimate: a local quadric fit (for comparison).

At every vertex ``p`` the vertices within distance ``r`` are written in the
frame ``(e1, e2, n_p)`` of the (outward, area-weighted) vertex normal, and the
height function ``z = a x^2 + b x y + c y^2 + d x + e y + f`` is fitted by
weighted least squares (weights ``(1 - (|q - p| / r)^2)^2``; one batched 6x6
solve for all vertices).  The Weingarten map of the fitted graph at ``x = y =
0`` gives the principal curvatures and directions (sign as in
:mod:`optimize.remesh.principal`: positive where the surface bends away from the
outward normal).  It is exact on quadrics and sensitive to noise, which the
volume-PCA estimate averages out.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..errors import ConfigError
from .principal import PrincipalFrames, oriented_surface, tangent_frames, vertex_indices


def quadric_frames(V, T=None, radius: float = 1.0, *, side=None, at=None, chunk: int = 1024) -> PrincipalFrames:
    """Principal frames from local quadric fits (vertices within ``radius``).

    V : (n, 3) float or a triangle Mesh; T : (t, 3) int.  side, at: as in
    :func:`optimize.remesh.principal.principal_frames`; chunk : points fitted at once.  Raises ConfigError when a
    vertex has fewer than 6 neighbours within ``radius`` (radius too small for
    the mesh resolution).
    """
    if not np.isfinite(radius) or radius <= 0:
        raise ConfigError(f"radius = {radius}, expected a positive length")
    mesh, N, _ = oriented_surface(V, T, side)
    at = vertex_indices(at, mesh.n_vertices)
    P, Np = mesh.V[at], N[at]
    E1, E2 = tangent_frames(Np)
    tree = cKDTree(mesh.V)
    c = np.empty((len(at), 6))
    for s in range(0, len(at), chunk):  # chunks bound the memory (pairs x 36 floats), each is vectorized
        sl = slice(s, s + chunk)
        c[sl] = _fit(mesh.V, tree, at[sl], P[sl], E1[sl], E2[sl], Np[sl], radius)
    a2, bxy, c2, gx, gy = c[:, 0], c[:, 1], c[:, 2], c[:, 3], c[:, 4]
    # Weingarten map of z = g(x, y) at the origin: II w = lambda I w (generalized symmetric)
    I = np.stack([np.stack([1 + gx * gx, gx * gy], 1), np.stack([gx * gy, 1 + gy * gy], 1)], 1)
    II = np.stack([np.stack([2 * a2, bxy], 1), np.stack([bxy, 2 * c2], 1)], 1)
    II /= np.sqrt(1 + gx * gx + gy * gy)[:, None, None]
    L = np.linalg.cholesky(I)
    Li = np.linalg.inv(L)
    M = Li @ II @ np.swapaxes(Li, 1, 2)
    lam, Y = np.linalg.eigh(-M)  # curvature positive where the graph bends below its tangent plane
    W = np.swapaxes(Li, 1, 2) @ Y  # (k, 2, 2) columns: parameter directions
    w1 = W[:, :, 1]  # the larger curvature
    t1 = w1[:, :1] * (E1 + gx[:, None] * Np) + w1[:, 1:] * (E2 + gy[:, None] * Np)
    t1 -= np.einsum("ij,ij->i", t1, Np)[:, None] * Np
    t1 /= np.maximum(np.linalg.norm(t1, axis=1, keepdims=True), 1e-300)
    nfit = -gx[:, None] * E1 - gy[:, None] * E2 + Np
    nfit /= np.linalg.norm(nfit, axis=1, keepdims=True)
    return PrincipalFrames(k1dir=t1, k2dir=np.cross(Np, t1), normals=Np.copy(), k1=lam[:, 1],
                           k2=lam[:, 0], pca_normals=nfit, radius=float(radius))


def _fit(V, tree, at, P, E1, E2, Np, radius) -> np.ndarray:
    """(k, 6) coefficients ``a, b, c, d, e, f`` of the weighted height-function fits at ``P (k, 3)``."""
    pairs = cKDTree(P).sparse_distance_matrix(tree, radius, output_type="ndarray")
    i, j = pairs["i"].astype(np.int64), pairs["j"].astype(np.int64)
    other = j != at[i]  # zero distances may or may not be listed: add every p itself once
    i, j = np.concatenate([i[other], np.arange(len(at))]), np.concatenate([j[other], at])
    count = np.bincount(i, minlength=len(at))
    if np.any(count < 6):
        v = int(at[np.argmax(count < 6)])
        raise ConfigError(f"radius = {radius}: vertex {v} has only {int(count.min())} vertices within it, "
                          "expected at least 6 for a quadric fit (increase the radius)")
    D = V[j] - P[i]
    x, y, z = (np.einsum("ij,ij->i", D, E[i]) for E in (E1, E2, Np))
    w = (1 - (x * x + y * y + z * z) / radius ** 2) ** 2 + 1e-3
    scale = np.array([radius ** 2, radius ** 2, radius ** 2, radius, radius, 1.0])  # for conditioning
    Phi = np.stack([x * x, x * y, y * y, x, y, np.ones_like(x)], axis=1) / scale
    order = np.argsort(i, kind="stable")
    starts = np.concatenate([[0], np.cumsum(count)[:-1]])
    A = np.add.reduceat((w[:, None, None] * Phi[:, :, None] * Phi[:, None, :])[order], starts, axis=0)
    b = np.add.reduceat((w[:, None] * Phi * z[:, None])[order], starts, axis=0)
    A += 1e-10 * np.trace(A, axis1=1, axis2=2)[:, None, None] * np.eye(6)
    return np.linalg.solve(A, b[..., None])[..., 0] / scale
