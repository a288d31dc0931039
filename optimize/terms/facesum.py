"""Planar convex faces by the angle sum (paper section 2.2): ``phi_1 + ... + phi_k - (k - 2) pi = 0``.

A skew polygon has an angle sum below ``(k - 2) pi``; the sum reaches it for a
planar convex polygon, so a zero residual asks for planar *and* convex faces.
Triangles satisfy it identically and get no row.  The row is degenerate: every
angle is an even function of an out-of-plane displacement, so its gradient
vanishes at a planar face and solvers converge on it linearly (the paper's
methods add determinant rows on quads, ``optimize.terms.determinants``).  The
default method does not use it (see ``convexity``); the paper's methods do.

Block: ``vertices (n, 3)``.  One row per face of :func:`angle_sum_faces`, in that order.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from ..mesh.topology import Topology
from .angles import angle_rows, rows_at
from .variables import Layout


def angle_sum_faces(mesh: Mesh) -> np.ndarray:
    """(r,) int: the faces that get a row (every face with 4 or more vertices)."""
    return np.nonzero(mesh.face_sizes >= 4)[0]


def face_corners(topology: Topology, faces: np.ndarray) -> np.ndarray:
    """(len(faces), kmax) int: corner indices of the given faces, ``-1`` padded."""
    sizes = topology.face_sizes[faces]
    k = int(sizes.max(initial=0))
    j = np.arange(k)[None, :]
    return np.where(j < sizes[:, None], topology.offsets[faces][:, None] + j, -1)


def rows(mesh: Mesh, faces: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows as corner sets: ``C (r, k)`` the corners of ``faces`` (default
    :func:`angle_sum_faces`; ``-1`` padded), signs ``(k,)`` (ones) and offsets ``(r,)``
    ``(size - 2) pi``; row ``i`` is ``sum_s signs[s] angle(C[i, s]) - offset[i]`` over the
    corners ``C[i, s] >= 0`` (both methods build on this)."""
    t = mesh.topology
    faces = angle_sum_faces(mesh) if faces is None else np.asarray(faces, dtype=np.int64)
    C = face_corners(t, faces)
    return C, np.ones(C.shape[1]), (t.face_sizes[faces] - 2) * np.pi


def terms(x: np.ndarray, layout: Layout, mesh: Mesh,
          faces: np.ndarray | None = None) -> tuple[np.ndarray, sp.csr_matrix]:
    """Residual ``(r,)`` (radians, <= 0 up to rounding) and Jacobian ``(r, layout.size)``."""
    return angle_rows(x, layout, mesh, *rows(mesh, faces))


def at_positions(mesh: Mesh, V: np.ndarray, faces: np.ndarray | None = None) -> tuple[np.ndarray, sp.csr_matrix]:
    """The rows at positions ``V (n, 3)``, the angle sum defect per face of ``faces`` (default
    :func:`angle_sum_faces`): residual ``(p,)`` and Jacobian ``(p, 3 n)`` with columns ``x = V.ravel()``
    (the unknowns are the vertices alone)."""
    return rows_at(mesh, V, *rows(mesh, faces))
