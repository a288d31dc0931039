"""Fixed vertices: which vertices the optimizer may not move.

Fixed vertices are not constrained by residual rows: their coordinates are
removed from the unknowns, so they stay exactly where they are.
"""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from ..mesh import Mesh


def corner_vertices(mesh: Mesh) -> np.ndarray:
    """(k,) int: boundary vertices with one face (the corners of a quad patch)."""
    t = mesh.topology
    return np.nonzero(t.is_boundary_vertex & (t.star_size == 1))[0]


def resolve(mesh: Mesh, fixed) -> np.ndarray:
    """(k,) int sorted unique vertex indices for ``fixed``.

    fixed : None | "none" | "boundary" | "corners" | sequence of vertex indices.
    Raises :class:`ConfigError` naming the value for anything else or an index out of range.
    """
    if fixed is None or (isinstance(fixed, str) and fixed == "none"):
        return np.zeros(0, dtype=np.int64)
    if isinstance(fixed, str):
        if fixed == "boundary":
            return np.nonzero(mesh.topology.is_boundary_vertex)[0]
        if fixed == "corners":
            return corner_vertices(mesh)
        raise ConfigError(f"fixed: {fixed!r} is not known, expected 'none', 'boundary', 'corners' "
                          "or a list of vertex indices")
    idx = np.asarray(fixed)
    if idx.size == 0:
        return np.zeros(0, dtype=np.int64)
    if idx.ndim != 1 or not np.issubdtype(idx.dtype, np.integer):
        raise ConfigError(f"fixed: expected a 1-d list of integer vertex indices, got {idx.dtype} "
                          f"array of shape {idx.shape}")
    bad = (idx < 0) | (idx >= mesh.n_vertices)
    if bad.any():
        raise ConfigError(f"fixed: vertex index {int(idx[bad][0])} out of range, expected "
                          f"0..{mesh.n_vertices - 1}")
    return np.unique(idx).astype(np.int64)
