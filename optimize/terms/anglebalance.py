"""Angle balance at conical vertices: ``w1 - w2 + w3 - w4 = 0`` (paper, Geometry Fact 1).

At every interior valence-4 vertex (``topology.interior_valence4``) with
corner angles ``w1..w4`` in cyclic order.  The normal-axis formulation
(``terms.conical``) alone also admits degenerate solutions where two
neighbouring faces become coplanar (any three planes touch a cone); the angle
balance rules them out, so the conical target uses both.  Not quadratic
(gradients in ``terms.angles``).

Block: ``vertices (n, 3)``.  One row per vertex.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh import Mesh
from .angles import angle_rows, rows_at
from .variables import Layout

SIGNS = np.array([1.0, -1.0, 1.0, -1.0])


def rows(mesh: Mesh, which: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows as corner sets: ``C (p, 4)`` star corners of the interior valence-4 vertices
    (``which`` picks positions in ``interior_valence4``), signs ``(4,)`` and offsets ``(p,)``;
    row ``i`` is ``sum_s signs[s] angle(C[i, s]) - offset[i]`` (both methods build on this)."""
    t = mesh.topology
    cv = t.interior_valence4 if which is None else t.interior_valence4[which]
    C = t.star_corners[cv, :4]
    return C, SIGNS, np.zeros(len(C))


def terms(x: np.ndarray, layout: Layout, mesh: Mesh, parts: bool = False,
          which: np.ndarray | None = None):
    """Residual ``(p,)`` and Jacobian ``(p, layout.size)`` (and, with ``parts``, the
    four per-corner Jacobians, each within one face, that sum to it).

    which : (p',) int positions in ``interior_valence4`` to restrict the rows to.
    """
    return angle_rows(x, layout, mesh, *rows(mesh, which), parts=parts)


def at_positions(mesh: Mesh, V: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
    """The rows at positions ``V (n, 3)``, ``w1 - w2 + w3 - w4`` per interior valence-4 vertex: residual ``(p,)`` and
    Jacobian ``(p, 3 n)`` with columns ``x = V.ravel()`` (the unknowns are the vertices alone)."""
    return rows_at(mesh, V, *rows(mesh))
