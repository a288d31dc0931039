"""Clean-up of the clipped cells along the boundary of a remeshed surface.

Where the boundary passes just beyond an iso-line, clipping leaves a sliver:
a thin triangle, quad or pentagon whose corners next to the inner vertices
are close to 180 degrees.  An optimizer is free to push such a corner past
180 degrees (a dented panel).  Snapping removes the sliver instead: each inner
vertex of a small boundary cell is collapsed onto the nearest boundary vertex
of that cell, so the full cell behind it becomes the boundary cell (its
vertices move by the sliver's width, along the surface's boundary).  Boundary
edges much shorter than the target length are collapsed, and boundary
vertices left in one face only (a straight corner) are taken out.

:func:`optimize.remesh.isolines.extract` does the same in the parameter plane; this
module works on any polygon mesh (the seamless branch's traced meshes).
"""
from __future__ import annotations

import numpy as np

from ..errors import MeshError
from ..mesh import Mesh
from ..mesh.measures import edge_lengths, face_areas
from .isolines import least_per_key


def _collapse(F: np.ndarray, rep: np.ndarray, remove: np.ndarray) -> np.ndarray:
    """Faces ``F (m, k)`` with every vertex replaced by ``rep[v]``, the vertices ``remove (n,) bool``
    and repeated corners taken out, and faces left with fewer than three corners dropped."""
    G = np.where((F >= 0) & ~remove[np.maximum(F, 0)], rep[np.maximum(F, 0)], -1)
    G = np.take_along_axis(G, np.argsort(G < 0, axis=1, kind="stable"), axis=1)
    nxt = np.roll(G, -1, axis=1)
    last = (G >= 0).sum(1) - 1
    nxt[np.arange(len(G)), last] = G[:, 0]
    drop = (G < 0) | (G == nxt)
    order = np.argsort(drop, axis=1, kind="stable")
    G = np.take_along_axis(G, order, axis=1)
    keep = (~drop).sum(1)
    G[np.arange(G.shape[1])[None, :] >= keep[:, None]] = -1
    return G[keep >= 3]


def snap_slivers(mesh: Mesh, corners: np.ndarray, edge_length: float, *, min_area: float = 0.25,
                 merge: float = 0.35, rounds: int = 6) -> tuple[Mesh, np.ndarray]:
    """Collapse small boundary cells onto the boundary and merge close boundary vertices.

    mesh : polygon Mesh with a boundary; corners : (c,) int vertices at corners of
    the input boundary (never moved); edge_length : target edge length ``h``.
    A boundary cell is small below ``min_area h^2``; boundary edges shorter than
    ``merge h`` are collapsed onto their corner (else their first) vertex; a
    boundary vertex (not a corner) in one face only is taken out of it.
    Returns ``(mesh, corners)`` renumbered.  A round whose result would not be a
    manifold mesh is not applied (the mesh of the round before is returned).
    """
    current, corners = mesh, np.asarray(corners, dtype=np.int64)
    for _ in range(rounds):
        V, F, t = current.V, current.F, current.topology
        is_corner = np.zeros(len(V), dtype=bool)
        is_corner[corners] = True
        on_ring = t.is_boundary_vertex
        rep = np.arange(len(V))
        # 1. short boundary edges: the non-corner end goes to the other end
        be = t.edges[t.is_boundary_edge]
        short = edge_lengths(current)[t.is_boundary_edge] < merge * edge_length
        be = be[short & ~(is_corner[be[:, 0]] & is_corner[be[:, 1]])]
        be = np.where(is_corner[be[:, 1:2]], be[:, ::-1], be)  # (kept, dropped)
        if len(be):
            _, first = np.unique(be[:, 1], return_index=True)
            be = be[first]
            be = be[~np.isin(be[:, 0], be[:, 1])]  # no chains in one round
            rep[be[:, 1]] = be[:, 0]
        # 2. inner vertices of small boundary cells go to their nearest boundary neighbour in the cell
        small = (face_areas(current) < min_area * edge_length ** 2) & on_ring[np.maximum(F, 0)].any(1)
        if np.any(small):
            sel = small[t.corner_face]  # the edges of the small cells, from the mesh's own corners
            hs, a, b = t.corner_face[sel], t.corner_vertex[sel], t.corner_next_vertex[sel]
            i, r = np.concatenate([a, b]), np.concatenate([b, a])
            pick = ~on_ring[i] & on_ring[r] & (rep[r] == r)
            i, r = i[pick], r[pick]
            if len(i):
                k = least_per_key(i, np.linalg.norm(V[i] - V[r], axis=1))
                rep[i[k]] = r[k]
            # a small cell with no inner vertex (it cuts a corner of the boundary): its shortest
            # edge goes, the end that is not a corner onto the other
            bare = ~np.bincount(hs, ~on_ring[a], minlength=len(F)).astype(bool)
            ok = bare[hs] & ~(is_corner[a] & is_corner[b]) & (rep[a] == a) & (rep[b] == b)
            if ok.any():
                hs, a, b = hs[ok], a[ok], b[ok]
                a, b = np.where(is_corner[a], a, b), np.where(is_corner[a], b, a)  # (kept, dropped)
                k = least_per_key(hs, np.linalg.norm(V[a] - V[b], axis=1))
                a, b = a[k], b[k]
                _, u = np.unique(b, return_index=True)
                a, b = a[u], b[u]
                keep = ~np.isin(a, b)
                rep[b[keep]] = a[keep]
        # 3. boundary vertices in one face only (not corners): straight corners, taken out
        lone = on_ring & (t.valence == 2) & ~is_corner & (rep == np.arange(len(V)))
        moved = rep != np.arange(len(V))
        lone[rep[moved]] = False  # a vertex something collapses onto stays
        if np.all(rep == np.arange(len(V))) and not lone.any():
            break
        G = _collapse(F, rep, lone)
        used = np.unique(G[G >= 0])
        remap = np.full(len(V), -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        try:
            nxt = Mesh(V[used], np.where(G >= 0, remap[np.maximum(G, 0)], -1), name=current.name)
            nxt.topology.boundary_loops  # noqa: B018 -- raises on a non-manifold result
        except MeshError:
            break
        nxt.notes = list(current.notes)
        c = remap[corners]
        current, corners = nxt, np.sort(c[c >= 0])
    return current, corners
