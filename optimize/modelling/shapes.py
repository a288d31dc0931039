"""Parametric quad meshes that are PQ, conical or circular by construction.

These are the fixtures of the test suite and the raw material of the built-in
designs: any size, any scale, seeded noise.
"""
from __future__ import annotations

import numpy as np

from ..mesh import Mesh


def grid_faces(nu: int, nv: int, closed_u: bool = False) -> np.ndarray:
    """(m, 4) int: quads of an ``nu x nv`` vertex grid (index ``i * nv + j``).

    ``closed_u`` wraps the ``u`` direction (a cylinder-like strip).
    """
    iu = np.arange(nu if closed_u else nu - 1)
    jv = np.arange(nv - 1)
    I, J = np.meshgrid(iu, jv, indexing="ij")
    I, J = I.ravel(), J.ravel()
    I1 = (I + 1) % nu
    return np.stack([I * nv + J, I1 * nv + J, I1 * nv + J + 1, I * nv + J + 1], axis=1)


def grid(nu: int, nv: int, size: tuple[float, float] = (1.0, 1.0), height=None, name: str = "grid") -> Mesh:
    """A ``nu x nv`` vertex grid over ``[0, size]``; ``height(x, y)`` lifts it (a height field)."""
    x = np.linspace(0.0, size[0], nu)
    y = np.linspace(0.0, size[1], nv)
    X, Y = np.meshgrid(x, y, indexing="ij")
    Z = np.zeros_like(X) if height is None else height(X, Y)
    V = np.stack([X.ravel(), Y.ravel(), np.asarray(Z, dtype=float).ravel()], axis=1)
    return Mesh(V, grid_faces(nu, nv), name=name)


def translational(a: np.ndarray, b: np.ndarray, name: str = "translational") -> Mesh:
    """The translational net ``a_i + b_j`` of two polylines ``a (nu, 3)``, ``b (nv, 3)``: PQ exactly."""
    V = (a[:, None, :] + b[None, :, :]).reshape(-1, 3)
    return Mesh(V, grid_faces(len(a), len(b)), name=name)


def revolution(profile: np.ndarray, n_around: int, sweep: float = 2 * np.pi,
               name: str = "revolution") -> Mesh:
    """Surface of revolution about the z axis: meridians x parallels.

    profile : (k, 2) float, ``(radius, height)`` points of the meridian.
    n_around : number of meridians; with ``sweep = 2 pi`` the mesh is closed
        around the axis, otherwise ``n_around`` meridians span ``sweep``.

    Planar, conical and circular by construction (every quad is an isosceles
    trapezoid; the faces around a vertex touch a cone with the z axis direction).
    """
    profile = np.asarray(profile, dtype=float)
    closed = np.isclose(sweep, 2 * np.pi)
    t = np.linspace(0.0, sweep, n_around, endpoint=not closed)
    r, h = profile[:, 0], profile[:, 1]
    V = np.stack([r[None, :] * np.cos(t)[:, None], r[None, :] * np.sin(t)[:, None],
                  np.broadcast_to(h[None, :], (n_around, len(r)))], axis=2).reshape(-1, 3)
    return Mesh(V, grid_faces(n_around, len(r), closed_u=closed), name=name)


def dome_profile(radius: float = 10.0, rise: float = 4.0, k: int = 8, top_gap: float = 0.15) -> np.ndarray:
    """(k, 2) float: meridian of a spherical-cap dome, stopping short of the pole."""
    R = (radius ** 2 + rise ** 2) / (2 * rise)
    a0 = np.arcsin(min(radius / R, 1.0))
    a = np.linspace(a0, top_gap * a0, k)
    return np.stack([R * np.sin(a), R * np.cos(a) - (R - rise)], axis=1)


def perturbed(mesh: Mesh, amount: float, seed: int = 0, name: str | None = None) -> Mesh:
    """``mesh`` with every vertex moved by seeded noise of ``amount`` x mean edge length."""
    from ..mesh.measures import edge_lengths

    rng = np.random.default_rng(seed)
    h = edge_lengths(mesh).mean()
    return mesh.with_vertices(mesh.V + amount * h * rng.standard_normal(mesh.V.shape),
                              name=name or f"{mesh.name}+noise")


def capped_cylinder(radius: float = 1.0, length: float = 2.850626, n_around: int = 20, rings: int = 11,
                    name: str = "cylinder") -> Mesh:
    """A closed cylinder about the y axis: ``n_around x (rings - 1)`` quads and two ``n_around``-gon caps.

    ``rings`` circles of ``n_around`` vertices from ``y = -length / 2`` to ``+length / 2``
    (the defaults: 220 vertices, 200 quads and two 20-gons).  Planar (every quad a
    rectangle, every cap a regular polygon), conical (the node axes are the
    radial directions) and circular by construction; outward normals.
    """
    t = 2 * np.pi * np.arange(n_around) / n_around
    y = np.linspace(-length / 2, length / 2, rings)
    V = np.stack([np.broadcast_to(radius * np.cos(t), (rings, n_around)),
                  np.broadcast_to(y[:, None], (rings, n_around)),
                  np.broadcast_to(-radius * np.sin(t), (rings, n_around))], axis=2).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(rings - 1), np.arange(n_around), indexing="ij")
    a = (i * n_around + j).ravel()
    b = (i * n_around + (j + 1) % n_around).ravel()
    quads = np.stack([a, b, b + n_around, a + n_around], axis=1)
    start = np.arange(n_around)[::-1]  # the cap at -y, seen from outside (-y): clockwise in x, z
    end = (rings - 1) * n_around + np.arange(n_around)
    faces = [f.tolist() for f in quads] + [start.tolist(), end.tolist()]
    return Mesh(V, faces, name=name)
