"""The polygon mesh: vertex positions apart from connectivity.

A mesh is ``V : (n, 3) float64`` plus faces as a padded ``F : (m, k) int64``
array, ``-1`` in unused slots (quads are ``k = 4``; a mesh with one 20-gon cap
has ``k = 20``).  Faces are stored counter-clockwise seen from the side the
normals point to.  Connectivity (:class:`optimize.mesh.topology.Topology`) is derived
once from ``F`` and cached; positions never change it, so
:meth:`Mesh.with_vertices` shares the topology of the original.

Construction validates everything a later stage relies on and raises
:class:`MeshError` with the facts: NaN/inf coordinates, face indices out of
range, repeated vertices in a face, zero-length edges (relative to the median
edge, so one stray vertex far away does not make the others coincide), quads
and polygons of zero area (collinear vertices, slivers, bow-ties: area at most
:data:`ZERO_AREA` times the face's longest edge squared: a panel that cannot be
cut; a zero-area triangle is only noted), non-manifold edges
and vertices, an empty mesh.  Every check is scale-free (coordinates are
scaled by a power of two first, which is exact), so a mesh in micrometres or
at 1e300 is judged like the same mesh in metres.  A fixable orientation inconsistency is fixed and
recorded in :attr:`Mesh.notes`.
"""
from __future__ import annotations

import logging
from functools import cached_property
from typing import Sequence

import numpy as np

from ..errors import MeshError

log = logging.getLogger(__name__)

#: A face is degenerate (refused) when its area is at most this fraction of its longest edge
#: squared: a 1 m panel narrower than 0.1 nm, or collinear corners up to rounding.
ZERO_AREA = 1e-10
#: An edge is zero-length when it is at most this fraction of the median edge length.
ZERO_EDGE = 1e-14
#: Padded arrays (faces x largest face, vertices x largest star) may hold at most PAD_FACTOR
#: times the mesh's face corners, or PAD_FLOOR slots: one 5000-gon among small faces, or a fan
#: of 5000 triangles around one vertex, would otherwise cost (faces or vertices) x 5000.
PAD_FACTOR = 8
PAD_FLOOR = 1 << 20


def padding_limit(corners: int) -> int:
    """Largest padded face or star array allowed for a mesh of ``corners`` face corners."""
    return max(PAD_FACTOR * corners, PAD_FLOOR)


def unit_exponent(V: np.ndarray) -> int:
    """``e`` such that ``np.ldexp(V, -e)`` has coordinates in [-1, 1] (exact: a power of two).

    Scale-free computations (ratios, angles) on the scaled array give the same bits
    as on ``V`` in the normal range, and neither overflow nor underflow at 1e300 or
    1e-300.  ``V``: any float array (0 for an empty or all-zero one).
    """
    top = float(np.abs(V).max(initial=0.0))
    return int(np.frexp(top)[1]) if np.isfinite(top) and top > 0 else 0


def pad_faces(faces: Sequence[Sequence[int]]) -> np.ndarray:
    """Pack a list of index lists into a padded ``(m, k)`` int64 array (``-1`` fill)."""
    if len(faces) == 0:
        return np.zeros((0, 3), dtype=np.int64)
    k = max(len(f) for f in faces)
    F = np.full((len(faces), k), -1, dtype=np.int64)
    for i, f in enumerate(faces):
        F[i, : len(f)] = f
    return F


class Mesh:
    """A polygon mesh with cached topology.

    Parameters
    ----------
    V : (n, 3) float
        Vertex positions.
    F : (m, k) int, or a sequence of index sequences
        Faces, padded with ``-1``; a ragged list is padded for you.
    name : str
        Used in messages (a file name, a shape name).
    check : bool
        Validate (default).  Only internal code that derives a mesh from an
        already validated one passes ``False``.
    """

    def __init__(self, V, F, name: str = "mesh", *, check: bool = True, _topology=None):
        V = np.array(V, dtype=np.float64, copy=check or None)  # never alias the caller
        if not isinstance(F, np.ndarray) or F.dtype == object:
            F = pad_faces(F) if len(F) and not np.isscalar(F[0]) else np.asarray(F)
        F = np.array(F, dtype=np.int64, copy=check or None)
        self.name = name
        self.notes: list[str] = []
        if check:
            V, F, notes = _validated(V, F, name)
            for msg in notes:
                log.warning(msg)
            self.notes.extend(notes)
        self.V = V
        self.F = F
        self.V.setflags(write=False)
        self.F.setflags(write=False)
        self._topology = _topology
        if check and _topology is None:
            self._topology = self._build_topology()

    # -- derived data -----------------------------------------------------
    def _build_topology(self):
        from .topology import Topology

        topo = Topology(self.F, len(self.V), name=self.name)
        if topo.flipped_faces.size:
            F = self.F.copy()
            F.setflags(write=True)
            for f in topo.flipped_faces:  # a repair done once, not a kernel
                s = topo.face_sizes[f]
                F[f, :s] = F[f, :s][::-1]
            msg = (f"{self.name}: {topo.flipped_faces.size} face(s) had inconsistent "
                   f"orientation and were flipped (first: {topo.flipped_faces[:5].tolist()})")
            log.warning(msg)
            self.notes.append(msg)
            F.setflags(write=False)
            self.F = F
            topo = Topology(self.F, len(self.V), name=self.name)
        if not topo.orientable:
            msg = f"{self.name}: the surface is not orientable (e.g. a Moebius band)"
            log.info(msg)
            self.notes.append(msg)
        return topo

    @property
    def topology(self):
        """:class:`optimize.mesh.topology.Topology` of the faces (computed once)."""
        if self._topology is None:
            self._topology = self._build_topology()
        return self._topology

    @property
    def n_vertices(self) -> int:
        return int(self.V.shape[0])

    @property
    def n_faces(self) -> int:
        return int(self.F.shape[0])

    @cached_property
    def face_sizes(self) -> np.ndarray:
        """(m,) int: number of vertices of each face."""
        return (self.F >= 0).sum(axis=1)

    @property
    def is_quad(self) -> bool:
        """True when every face is a quad."""
        return bool(self.F.shape[1] == 4 and np.all(self.face_sizes == 4))

    def faces_list(self) -> list[list[int]]:
        """Faces as Python lists (for writers and small utilities)."""
        return [row[row >= 0].tolist() for row in self.F]

    def bbox_diagonal(self) -> float:
        """Length of the bounding-box diagonal (the scale used by relative measures)."""
        e = unit_exponent(self.V)
        W = np.ldexp(self.V, -e)
        return float(np.ldexp(np.linalg.norm(W.max(axis=0) - W.min(axis=0)), e))

    def with_vertices(self, V: np.ndarray, name: str | None = None) -> "Mesh":
        """A mesh with the same faces and topology and new positions ``V (n, 3)``.

        Raises :class:`MeshError` for a shape mismatch or non-finite values.
        """
        V = np.array(V, dtype=np.float64)
        if V.shape != self.V.shape:
            raise MeshError(f"{self.name}: new vertex array has shape {V.shape}, "
                            f"expected {self.V.shape}")
        if not np.all(np.isfinite(V)):
            bad = int(np.argwhere(~np.isfinite(V))[0, 0])
            raise MeshError(f"{self.name}: vertex {bad} is not finite: {V[bad].tolist()}")
        out = Mesh(V, self.F, name or self.name, check=False, _topology=self.topology)
        out.notes = list(self.notes)
        return out

    def triangulate(self) -> np.ndarray:
        """(t, 3) int: fan triangulation of every face (for closest-point queries)."""
        sizes = self.face_sizes
        tris = []
        for j in range(1, self.F.shape[1] - 1):
            sel = sizes > j + 1
            tris.append(np.stack([self.F[sel, 0], self.F[sel, j], self.F[sel, j + 1]], axis=1))
        return np.concatenate(tris, axis=0) if tris else np.zeros((0, 3), dtype=np.int64)

    def __repr__(self) -> str:
        sizes = np.bincount(self.face_sizes) if self.n_faces else []
        desc = ", ".join(f"{c} {k}-gons" for k, c in enumerate(sizes) if c)
        return f"Mesh({self.name!r}: {self.n_vertices} vertices, {desc})"


def _validated(V: np.ndarray, F: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Check arrays; return contiguous copies and notes.  Raises MeshError with the facts."""
    if V.ndim != 2 or V.shape[1] != 3:
        raise MeshError(f"{name}: vertices have shape {V.shape}, expected (n, 3)")
    if F.ndim != 2:
        raise MeshError(f"{name}: faces have shape {F.shape}, expected (m, k)")
    if V.shape[0] == 0 or F.shape[0] == 0:
        raise MeshError(f"{name}: empty mesh ({V.shape[0]} vertices, {F.shape[0]} faces), "
                        "expected at least one face")
    bad = ~np.isfinite(V)
    if bad.any():
        i = int(np.argwhere(bad)[0, 0])
        raise MeshError(f"{name}: vertex {i} has a non-finite coordinate {V[i].tolist()}, "
                        "expected finite numbers")
    valid = F >= 0
    # padding must be trailing
    if np.any(~valid[:, :-1] & valid[:, 1:]):
        f = int(np.argwhere(~valid[:, :-1] & valid[:, 1:])[0, 0])
        raise MeshError(f"{name}: face {f} has -1 before a vertex index, expected padding at the end")
    sizes = valid.sum(axis=1)
    if np.any(sizes < 3):
        f = int(np.argmax(sizes < 3))
        raise MeshError(f"{name}: face {f} has {sizes[f]} vertices, expected at least 3")
    if np.any(F >= V.shape[0]) or np.any(F < -1):
        f, j = (int(x) for x in np.argwhere((F >= V.shape[0]) | (F < -1))[0])
        raise MeshError(f"{name}: face {f} refers to vertex {F[f, j]}, expected 0..{V.shape[0] - 1}")
    # repeated vertex in a face
    S = np.sort(np.where(valid, F, -np.arange(1, F.shape[1] + 1)[None, :] - 1), axis=1)
    rep = np.any(S[:, 1:] == S[:, :-1], axis=1)
    if rep.any():
        f = int(np.argmax(rep))
        raise MeshError(f"{name}: face {f} repeats a vertex: {F[f][F[f] >= 0].tolist()}, "
                        "expected distinct vertices")
    used = np.bincount(F[valid], minlength=V.shape[0])
    limit = padding_limit(int(valid.sum()))
    if F.size > limit:
        f = int(np.argmax(sizes))
        raise MeshError(f"{name}: face {f} has {sizes[f]} vertices; the {F.shape[0]} faces padded to that "
                        f"size need {F.size} slots, over the limit of {limit} ({PAD_FACTOR} x the "
                        f"{int(valid.sum())} face corners); expected polygons of comparable size")
    if V.shape[0] * (int(used.max()) + 1) > limit:
        v = int(np.argmax(used))
        raise MeshError(f"{name}: vertex {v} is a corner of {int(used[v])} faces; the {V.shape[0]} vertex "
                        f"stars padded to that size need {V.shape[0] * (int(used[v]) + 1)} slots, over the "
                        f"limit of {limit} ({PAD_FACTOR} x the {int(valid.sum())} face corners); expected "
                        "vertices of comparable valence (a fan of triangles around one point?)")
    notes = _check_degenerate(np.ldexp(V, -unit_exponent(V)), F, valid, name)
    return np.ascontiguousarray(V), np.ascontiguousarray(F), notes


def area_ratio(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """(m,) float: area of each face of ``V (n, 3)``, ``F (m, k)`` (padded with -1) divided by its
    longest edge squared; scale-free (0 for collinear corners; a face is degenerate at
    ``<= ZERO_AREA``).  Faces must have distinct, in-range indices."""
    W = np.ldexp(np.asarray(V, dtype=np.float64), -unit_exponent(V))
    return _edges_and_areas(W, F)[3]


def _edges_and_areas(W: np.ndarray, F: np.ndarray):
    """Per corner (valid slots of ``F (m, k)`` in row order): face ``rows (c,)``, start and end
    vertex ``a, b (c,)``, and per face the area ratio ``(m,)``, edge ``length (c,)``, longest
    edge ``(m,)``.  Work is per corner, never per padded slot (one big face among many small
    ones costs its own size only); faces of one size take a faster path."""
    valid = F >= 0
    m, k = F.shape
    with np.errstate(invalid="ignore", over="ignore"):
        if valid.all():  # every face has k corners: no padding
            rows = np.repeat(np.arange(m), k)
            a, b = F.ravel(), np.roll(F, -1, axis=1).ravel()
            d = W[b] - W[a]
            length = np.sqrt(np.einsum("ij,ij->i", d, d))
            longest = length.reshape(m, k).max(axis=1)
            P = W[F]
            if k == 3:
                A = _cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
            elif k == 4:  # twice the vector area of a quad: the cross product of its diagonals
                A = _cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])
            else:
                Q = P - P[:, :1]
                A = _cross(Q[:, :-1].reshape(-1, 3), Q[:, 1:].reshape(-1, 3)).reshape(m, k - 1, 3).sum(axis=1)
        else:
            sizes = valid.sum(axis=1)
            rows = np.repeat(np.arange(m), sizes)
            a = F[valid]
            starts = np.repeat(np.cumsum(sizes) - sizes, sizes)
            after = np.arange(len(a)) + 1
            b = a[np.where(after - starts < np.repeat(sizes, sizes), after, starts)]
            d = W[b] - W[a]
            length = np.sqrt(np.einsum("ij,ij->i", d, d))
            longest = np.zeros(m)
            np.maximum.at(longest, rows, length)
            o = W[F[rows, 0]]
            cr = _cross(W[a] - o, W[b] - o)  # Newell about the first corner: twice the vector area
            A = np.stack([np.bincount(rows, cr[:, j], minlength=m) for j in range(3)], axis=1)
        area = 0.5 * np.sqrt(np.einsum("ij,ij->i", A, A))
        ratio = np.nan_to_num(area / longest ** 2)
    return rows, a, b, ratio, length, longest


def _cross(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """(r, 3) cross products of ``u, w (r, 3)`` (by columns: faster than ``np.cross``)."""
    out = np.empty_like(u)
    out[:, 0] = u[:, 1] * w[:, 2] - u[:, 2] * w[:, 1]
    out[:, 1] = u[:, 2] * w[:, 0] - u[:, 0] * w[:, 2]
    out[:, 2] = u[:, 0] * w[:, 1] - u[:, 1] * w[:, 0]
    return out


def _check_degenerate(W: np.ndarray, F: np.ndarray, valid: np.ndarray, name: str) -> list[str]:
    """Zero-length edges and zero-area faces of positions ``W (n, 3)`` (scaled to [-1, 1]),
    faces ``F (m, k)``.  Raises :class:`MeshError` naming the face for a zero-length edge and
    for a zero-area quad or polygon (a panel that cannot be cut); a zero-area triangle (a
    modeller's sliver in a triangulated surface, harmless to a reference or remeshing input)
    is returned as a note."""
    rows, a, b, ratio, length, longest = _edges_and_areas(W, F)
    median = float(np.median(length))
    zero = length <= ZERO_EDGE * median
    if zero.any():
        i = int(np.argmax(zero))
        rel = f" ({length[i] / median:.1e} of the median edge)" if length[i] > 0 else ""
        raise MeshError(f"{name}: face {int(rows[i])} has a zero-length edge {int(a[i])}-{int(b[i])}{rel}, "
                        "expected distinct vertex positions")
    flat = ratio <= ZERO_AREA
    if not flat.any():
        return []
    panels = flat & (valid.sum(axis=1) > 3)
    f = int(np.argmax(panels)) if panels.any() else int(np.argmax(flat))
    mine = np.flatnonzero(rows == f)
    j = int(mine[np.argmax(length[mine])])
    what = (f"face {f} {F[f][valid[f]].tolist()} has zero area ({ratio[f]:.1e} of its longest edge squared: "
            f"collinear corners, a sliver or a bow-tie)")
    hint = (f"; its edge {int(a[j])}-{int(b[j])} is {longest[f] / median:.1e} median edge lengths long "
            "(a stray vertex?)") if longest[f] > 1e6 * median else ""
    if panels.any():
        raise MeshError(f"{name}: {what}, expected at least {ZERO_AREA:g}{hint}")
    return [f"{name}: {int(flat.sum())} zero-area triangle(s), the first: {what}{hint}"]
