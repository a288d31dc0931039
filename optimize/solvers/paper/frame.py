"""A canonical frame of a vertex cloud: the paper's methods solve in it, so they move with their input.

The penalty method's Levenberg-Marquardt damping ``D = diag(J^T J)`` is Marquardt's
per-coordinate scaling: it depends on the directions of the coordinate axes, so a
rotated input took other steps (2.9e-2 of the diagonal apart after 12 iterations on
a perturbed dome).  The paper's methods therefore solve in the input's own frame:
``x = ((V - c) / h) R`` with ``c`` the mean vertex and ``h`` the mean edge length
(:func:`optimize.mesh.measures.normalization`) and ``R`` the rotation of
:func:`canonical_rotation`, which moves with the mesh (``R' = Q R`` for the input
``V Q^T``).  A rigid motion and a uniform scale then change the solver's input by
rounding only, and the result comes back by ``V = c + h x R^T``.  For an input whose
principal axes are the model axes (a roof with z up) the frame is the model's
own up to the order and signs of the axes, which leave ``D`` as it was.

The frame is well defined for every mesh:

- the axes are the principal axes of the vertex cloud (eigenvectors of its
  covariance), largest variance first;
- eigenvalues closer than ``GAP`` (relative to the largest) leave their axes
  undetermined (a surface of revolution: any horizontal pair); within such a
  group the first axis points to the vertex farthest from the other axes
  (:func:`_pick`: the lowest vertex index among those within ``TIE`` of the
  farthest), the next is perpendicular to it;
- each axis points where the cloud's third moment along it is positive; where
  that moment vanishes (a symmetric cloud: within ``SKEW`` of its scale) to the
  side of the vertex farthest along the axis (the lowest index at ties);
- the third axis is the cross product of the first two (a rotation, never a
  reflection: the strip determinants keep their signs).

Every rule uses the positions relative to the centre and the vertex indices, both
of which move with the mesh, and none compares quantities whose difference is
rounding unless they are equal to within ``TIE``, where the index decides.
"""
from __future__ import annotations

import numpy as np

GAP = 1e-3  # eigenvalues closer than this (relative to the largest) span one undetermined group
SKEW = 1e-6  # |third moment| / rms^3 below this: symmetric along the axis, the farthest vertex decides
TIE = 1e-8  # distances within this (relative) of the largest are ties, broken by the lowest vertex index


def _pick(t: np.ndarray) -> int:
    """The vertex of largest ``t (n,)``: the lowest index among those within ``TIE`` of the largest."""
    top = float(t.max(initial=0.0))
    return int(np.flatnonzero(t >= top - TIE * abs(top))[0])


def _orient(X: np.ndarray, u: np.ndarray) -> np.ndarray:
    """``u`` or ``-u``: the side of the positive third moment of ``X (n, 3)`` along it, else of the
    vertex farthest along it."""
    t = X @ u
    rms = float(np.sqrt(np.mean(t * t)))
    if rms == 0.0:
        return u
    skew = float(np.mean(t ** 3)) / rms ** 3
    if abs(skew) > SKEW:
        return u if skew > 0 else -u
    return u if t[_pick(np.abs(t))] >= 0 else -u


def _first_in(X: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A unit vector in the span of the orthonormal columns ``B (3, k)``: along one axis
    (``k = 1``) or towards the vertex farthest from the other directions (``k > 1``)."""
    if B.shape[1] == 1:
        return _orient(X, B[:, 0])
    P = X @ B  # (n, k) coordinates in the group's subspace
    p = P[_pick(np.einsum("ij,ij->i", P, P))]
    norm = float(np.linalg.norm(p))
    return B @ (p / norm) if norm > 0 else _orient(X, B[:, 0])


def canonical_rotation(X: np.ndarray) -> np.ndarray:
    """(3, 3) rotation ``R`` (orthonormal columns, ``det R = 1``) of the centred cloud ``X (n, 3)``:
    ``X R`` are the coordinates on its canonical axes (module docstring)."""
    X = np.asarray(X, dtype=np.float64)
    w, U = np.linalg.eigh(X.T @ X / max(len(X), 1))
    w, U = w[::-1], U[:, ::-1]  # largest first
    top = max(float(w[0]), np.finfo(float).tiny)
    groups, start = [], 0
    for i in range(1, 4):
        if i == 3 or w[i - 1] - w[i] > GAP * top:
            groups.append(U[:, start:i])
            start = i
    B = groups[0]
    e1 = _first_in(X, B)
    if B.shape[1] > 1:  # the rest of the first group, perpendicular to e1
        left, _, _ = np.linalg.svd(B - np.outer(e1, e1 @ B))
        B2 = left[:, :B.shape[1] - 1]  # any basis: _first_in depends on the span only
    else:
        B2 = groups[1]
    e2 = _first_in(X, B2)
    e2 = e2 - e1 * float(e1 @ e2)  # rounding only
    e2 /= np.linalg.norm(e2)
    return np.column_stack([e1, e2, np.cross(e1, e2)])
