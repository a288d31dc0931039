"""Connectivity of a polygon mesh, computed once from its faces.

Corners and half-edges share one index: corner ``c`` of face ``f`` (slot
``j``) is ``c = offsets[f] + j``, and the half-edge leaving that corner runs
from ``corner_vertex[c]`` to ``corner_next_vertex[c]`` inside face ``f``.

Arrays (``c`` corners, ``e`` edges, ``n`` vertices, ``m`` faces):

- ``face_sizes (m,)``, ``offsets (m + 1,)``
- ``corner_face, corner_vertex, corner_next_vertex, corner_prev_vertex,
  corner_next, corner_prev (c,)`` (the last two are corner indices)
- ``edges (e, 2)`` sorted vertex pairs, ``corner_edge (c,)`` edge of the
  half-edge leaving each corner, ``edge_faces (e, 2)`` (``-1`` on the boundary),
  ``twin (c,)`` the other half-edge of the same edge or ``-1``
- ``star_corners (n, s)`` corners around each vertex in cyclic order (counter-
  clockwise for faces stored counter-clockwise), ``-1`` padded; ``star_size (n,)``
- ``star_neighbors (n, s + 1)`` neighbouring vertices in the same cyclic order
- ``valence (n,)``, ``is_boundary_vertex (n,)``, ``boundary_loops`` (list of
  ``(L,)`` int arrays), ``component (n,)`` labels
- ``fair_triples (t, 3)`` vertex triples ``(a, v, b)`` where a mesh polyline
  runs straight ``a -> v -> b``: through interior valence-4 vertices (two
  triples each) and along the boundary through boundary valence-3 vertices
- ``polylines``: list of ``(L,)`` vertex index arrays built from those triples

Non-manifold edges (3+ faces) and vertices (2+ separate fans) raise
:class:`MeshError`.  Faces whose orientation disagrees with a neighbour are
listed in ``flipped_faces`` (the faces to flip to make the mesh consistent);
``orientable`` is False when no flip makes it consistent (a Moebius band).
"""
from __future__ import annotations

from functools import cached_property

import numpy as np

from ..errors import MeshError


class Topology:
    """Connectivity of a padded face array ``F (m, k)`` over ``n_vertices`` vertices."""

    def __init__(self, F: np.ndarray, n_vertices: int, name: str = "mesh"):
        self.name = name
        self.n_vertices = int(n_vertices)
        valid = F >= 0
        self.face_sizes = valid.sum(axis=1).astype(np.int64)
        self.n_faces = int(F.shape[0])
        self.offsets = np.concatenate([[0], np.cumsum(self.face_sizes)]).astype(np.int64)
        nc = int(self.offsets[-1])
        self.corner_face = np.repeat(np.arange(self.n_faces), self.face_sizes)
        self.corner_vertex = F[valid]
        local = np.arange(nc) - self.offsets[self.corner_face]
        size = self.face_sizes[self.corner_face]
        start = self.offsets[self.corner_face]
        self.corner_next = start + (local + 1) % size
        self.corner_prev = start + (local - 1) % size
        self.corner_next_vertex = self.corner_vertex[self.corner_next]
        self.corner_prev_vertex = self.corner_vertex[self.corner_prev]
        self._build_edges()
        self._check_orientation()
        self._build_stars()

    # -- edges, twins ------------------------------------------------------
    def _build_edges(self) -> None:
        a, b = self.corner_vertex, self.corner_next_vertex
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        key = lo * self.n_vertices + hi
        uniq, inv, counts = np.unique(key, return_inverse=True, return_counts=True)
        self.edges = np.stack([uniq // self.n_vertices, uniq % self.n_vertices], axis=1)
        self.corner_edge = inv
        if np.any(counts > 2):
            e = int(np.argmax(counts > 2))
            faces = np.unique(self.corner_face[inv == e]).tolist()
            raise MeshError(f"{self.name}: non-manifold edge {self.edges[e].tolist()} is shared by "
                            f"{int(counts[e])} faces {faces}, expected at most 2")
        order = np.argsort(inv, kind="stable")
        first = np.concatenate([[0], np.cumsum(counts)[:-1]])
        c0 = order[first]
        c1 = np.where(counts == 2, order[np.minimum(first + 1, len(order) - 1)], -1)
        self.twin = np.full(len(inv), -1, dtype=np.int64)
        two = counts == 2
        self.twin[c0[two]] = c1[two]
        self.twin[c1[two]] = c0[two]
        self.edge_faces = np.stack([self.corner_face[c0],
                                    np.where(two, self.corner_face[np.maximum(c1, 0)], -1)], axis=1)
        self.edge_corners = np.stack([c0, c1], axis=1)
        self.is_boundary_edge = ~two

    # -- orientation -------------------------------------------------------
    def _check_orientation(self) -> None:
        """Find faces to flip for a consistent orientation (2-colouring of the dual graph)."""
        c0, c1 = self.edge_corners[~self.is_boundary_edge].T
        same = self.corner_vertex[c0] == self.corner_vertex[c1]  # same direction: inconsistent
        self.orientable = True
        self.flipped_faces = np.zeros(0, dtype=np.int64)
        if not same.any():
            return
        import scipy.sparse as sp  # only for a mesh whose faces disagree on their orientation
        from scipy.sparse.csgraph import breadth_first_order, connected_components

        f0, f1 = self.corner_face[c0], self.corner_face[c1]
        m = self.n_faces
        G = sp.coo_matrix((np.ones(len(f0)), (f0, f1)), shape=(m, m)).tocsr()
        G = G + G.T
        parity_of = {}
        for x, y, s in zip(f0.tolist(), f1.tolist(), same.tolist()):
            parity_of[(x, y)] = parity_of[(y, x)] = s
        flip = np.zeros(m, dtype=bool)
        seen = np.zeros(m, dtype=bool)
        for root in range(m):  # one pass per connected component of the dual graph
            if seen[root]:
                continue
            order, pred = breadth_first_order(G, root, directed=False)
            seen[order] = True
            for f in order[1:]:  # repair walk, run once per mesh
                p = pred[f]
                flip[f] = flip[p] ^ parity_of[(int(p), int(f))]
        consistent_after = same == (flip[f0] ^ flip[f1])
        self.orientable = bool(consistent_after.all())
        if self.orientable:  # only a flip that repairs the mesh is proposed
            # flip the minority of each piece: one reversed face is fixed by flipping it
            label = connected_components(G, directed=False)[1]
            flipped = np.bincount(label, weights=flip)
            total = np.bincount(label)
            flip ^= (2 * flipped > total)[label]
            self.flipped_faces = np.nonzero(flip)[0]

    # -- vertex stars ------------------------------------------------------
    def _corner_at(self, he: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Corner at vertex ``v`` in the face of half-edge ``he`` (which has ``v`` as an end)."""
        ok = he >= 0
        h = np.maximum(he, 0)
        c = np.where(self.corner_vertex[h] == v, h, self.corner_next[h])
        return np.where(ok, c, -1)

    def _build_stars(self) -> None:
        cv = self.corner_vertex
        e_next = self.corner_edge
        e_prev = self.corner_edge[self.corner_prev]
        across_next = self._corner_at(self.twin, cv)
        across_prev = self._corner_at(self.twin[self.corner_prev], cv)
        n = self.n_vertices
        n_corners_at = np.bincount(cv, minlength=n)
        if np.any(n_corners_at == 0):
            v = int(np.argmax(n_corners_at == 0))
            raise MeshError(f"{self.name}: vertex {v} belongs to no face, expected every vertex used "
                            f"({int((n_corners_at == 0).sum())} unused)")
        # start corner per vertex: prefer a corner whose 'next' side is boundary
        prio = np.where(across_next < 0, 0, np.where(across_prev < 0, 1, 2))
        order = np.lexsort((prio, cv))
        first = np.concatenate([[0], np.cumsum(n_corners_at)[:-1]])
        start = order[first]
        via_prev = across_next[start] < 0
        via_prev |= across_prev[start] >= 0  # interior vertex or boundary on 'next' side
        smax = int(n_corners_at.max())
        star = np.full((n, max(smax, 4)), -1, dtype=np.int64)
        nbr = np.full((n, max(smax + 1, 5)), -1, dtype=np.int64)
        cur = start.copy()
        alive = np.ones(n, dtype=bool)
        count = np.zeros(n, dtype=np.int64)
        closed = np.zeros(n, dtype=bool)
        for step in range(smax):
            idx = np.nonzero(alive)[0]
            c = cur[idx]
            vp = via_prev[idx]
            star[idx, step] = c
            nbr[idx, step] = np.where(vp, self.corner_next_vertex[c], self.corner_prev_vertex[c])
            count[idx] += 1
            nxt = np.where(vp, across_prev[c], across_next[c])
            x = np.where(vp, e_prev[c], e_next[c])
            end = (nxt < 0) | (nxt == start[idx])
            closed[idx[nxt == start[idx]]] = True
            last = idx[nxt < 0]
            nbr[last, step + 1] = np.where(vp[nxt < 0], self.corner_prev_vertex[c[nxt < 0]],
                                           self.corner_next_vertex[c[nxt < 0]])
            go = ~end
            nn = nxt[go]
            cur[idx[go]] = nn
            via_prev[idx[go]] = e_next[nn] == x[go]
            alive[idx[end]] = False
            if not alive.any():
                break
        if np.any(count != n_corners_at):
            v = int(np.argmax(count != n_corners_at))
            raise MeshError(f"{self.name}: non-manifold vertex {v}: its {int(n_corners_at[v])} faces "
                            f"form more than one fan, expected one disk or half-disk")
        self.star_corners = star
        self.star_size = count
        self.star_neighbors = nbr
        self.is_boundary_vertex = ~closed
        self.valence = count + (~closed)

    # -- derived, cached -----------------------------------------------------
    @cached_property
    def star_faces(self) -> np.ndarray:
        """(n, s) int: faces around each vertex in cyclic order, ``-1`` padded."""
        return np.where(self.star_corners >= 0, self.corner_face[np.maximum(self.star_corners, 0)], -1)

    @cached_property
    def interior_valence4(self) -> np.ndarray:
        """(p,) int: interior vertices with exactly four faces (where conical is defined)."""
        return np.nonzero(~self.is_boundary_vertex & (self.star_size == 4))[0]

    @cached_property
    def interior_irregular(self) -> np.ndarray:
        """(q,) int: interior vertices with other than four faces (valence 3, 5, ...: irregular nodes)."""
        return np.nonzero(~self.is_boundary_vertex & (self.star_size != 4))[0]

    @cached_property
    def fair_triples(self) -> np.ndarray:
        """(t, 3) int: straight continuations ``(a, v, b)`` of mesh polylines."""
        inner = self.interior_valence4
        nb = self.star_neighbors[inner]
        t1 = np.stack([nb[:, 0], inner, nb[:, 2]], axis=1)
        t2 = np.stack([nb[:, 1], inner, nb[:, 3]], axis=1)
        bnd = np.nonzero(self.is_boundary_vertex & (self.star_size == 2))[0]
        nbb = self.star_neighbors[bnd]
        t3 = np.stack([nbb[:, 0], bnd, nbb[:, 2]], axis=1)
        return np.concatenate([t1, t2, t3], axis=0).astype(np.int64)

    @cached_property
    def polylines(self) -> list[np.ndarray]:
        """Mesh polylines (rows and columns), each an ``(L,)`` array of vertex indices.

        A closed polyline repeats its first vertex at the end.  Every edge lies
        on exactly one polyline.
        """
        key = {}
        for i, (a, b) in enumerate(self.edges.tolist()):
            key[(a, b)] = 2 * i
            key[(b, a)] = 2 * i + 1
        nde = 2 * len(self.edges)
        cont = np.full(nde, -1, dtype=np.int64)
        for a, v, b in self.fair_triples.tolist():
            cont[key[(a, v)]] = key[(v, b)]
            cont[key[(b, v)]] = key[(v, a)]
        has_pred = np.zeros(nde, dtype=bool)
        has_pred[cont[cont >= 0]] = True
        used = np.zeros(len(self.edges), dtype=bool)
        tail = lambda d: int(self.edges[d // 2, 1 - d % 2])  # noqa: E731
        head = lambda d: int(self.edges[d // 2, d % 2])  # noqa: E731
        lines = []
        starts = [d for d in range(nde) if not has_pred[d]] + list(range(nde))
        for d0 in starts:  # chaining done once per mesh
            if used[d0 // 2]:
                continue
            verts = [head(d0)]
            d = d0
            while d >= 0 and not used[d // 2]:
                used[d // 2] = True
                verts.append(tail(d))
                d = int(cont[d])
            lines.append(np.array(verts, dtype=np.int64))
        return lines

    @cached_property
    def boundary_loops(self) -> list[np.ndarray]:
        """Boundary loops as ``(L,)`` vertex index arrays (first vertex not repeated)."""
        be = self.edges[self.is_boundary_edge]
        if len(be) == 0:
            return []
        nb: dict[int, list[int]] = {}
        for a, b in be.tolist():
            nb.setdefault(a, []).append(b)
            nb.setdefault(b, []).append(a)
        seen: set[int] = set()
        loops = []
        # follow the face orientation where possible: start along a boundary half-edge
        bh = np.nonzero(self.twin < 0)[0]
        for h in bh.tolist():
            v0 = int(self.corner_vertex[h])
            if v0 in seen:
                continue
            loop = [v0, int(self.corner_next_vertex[h])]
            seen.update(loop)
            while True:
                a, b = loop[-2], loop[-1]
                c = [x for x in nb[b] if x != a]
                if not c or c[0] == loop[0]:
                    break
                loop.append(c[0])
                seen.add(c[0])
            loops.append(np.array(loop, dtype=np.int64))
        return loops

    @cached_property
    def component(self) -> np.ndarray:
        """(n,) int: connected component label of each vertex."""
        from .components import component_labels

        return component_labels(self.n_vertices, self.edges)

    @property
    def n_components(self) -> int:
        return int(self.component.max()) + 1
