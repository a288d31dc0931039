"""PQ strips: one row of quads between two polylines, the discrete developables.

A strip has rulings ``(a_i, b_i)``, ``i = 0..r-1``, and quads
``[a_i, a_(i+1), b_(i+1), b_i]``: open (``r - 1`` quads), closed (``r`` quads,
the last joins ``a_(r-1) b_(r-1)`` to ``a_0 b_0``) or closed with a half twist
(a Moebius band: the last quad joins ``a_(r-1) b_(r-1)`` to ``b_0 a_0``).
:func:`strip_mesh` numbers vertices ``a_i = 2 i``, ``b_i = 2 i + 1``;
:func:`strip_layouts` recovers the rulings of any strip mesh (any vertex
order, several strips as separate components) by walking its faces.

A strip whose quads are planar is a discrete developable surface: it unrolls
into the plane exactly (:func:`develop`), its Gauss image is a curve (the
face normals; :func:`gauss_image` measures how far each quad is from having
one normal), and consecutive rulings meet in the points ``r_i`` of the
singular curve (:func:`analyze_strip`).  Refinement by Chaikin or cubic
Lane-Riesenfeld on both boundary polylines is :func:`refine_strips` (the
strip-analysis half of this module is :mod:`optimize.modelling.strip_analysis`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import ConfigError, MeshError
from ..mesh import Mesh
from .curves import CURVE_SCHEMES, curve_operator

__all__ = ["StripLayout", "strip_faces", "strip_mesh", "join_meshes", "strip_layouts",
           "refine_strips", "ruling_points"]


@dataclass(frozen=True)
class StripLayout:
    """The rulings of one strip of a mesh.

    a, b : (r,) int
        Vertex indices of the ruling ends, in strip order.
    faces : (q,) int
        Face indices in strip order (face ``i`` between rulings ``i`` and ``i + 1``).
    closed : bool
    twist : bool
        Closed with a half twist: after ruling ``r - 1`` comes ``(b_0, a_0)``.
    """

    a: np.ndarray
    b: np.ndarray
    faces: np.ndarray
    closed: bool
    twist: bool

    @property
    def n_rulings(self) -> int:
        return int(len(self.a))

    @property
    def n_quads(self) -> int:
        return int(len(self.faces))


def strip_faces(r: int, closed: bool = False, twist: bool = False) -> np.ndarray:
    """(q, 4) int: quads of a strip with ``r`` rulings numbered ``a_i = 2 i, b_i = 2 i + 1``."""
    i = np.arange(r - 1)
    F = np.stack([2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1], axis=1)
    if closed:
        last = [2 * r - 2, 1, 0, 2 * r - 1] if twist else [2 * r - 2, 0, 1, 2 * r - 1]
        F = np.concatenate([F, np.array([last])])
    return F


def strip_mesh(a, b, *, closed: bool = False, twist: bool = False, name: str = "strip") -> Mesh:
    """The strip between polylines ``a (r, 3)`` and ``b (r, 3)`` (vertex ``2 i`` = a_i, ``2 i + 1`` = b_i).

    ``twist`` (with ``closed``) makes a Moebius band.  Raises ConfigError for
    mismatched or too short polylines.
    """
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.shape != b.shape or a.ndim != 2 or a.shape[1] != 3:
        raise ConfigError(f"{name}: strip sides have shapes {a.shape} and {b.shape}, expected two (r, 3)")
    if twist and not closed:
        raise ConfigError(f"{name}: twist=True needs closed=True (a half twist joins the two ends)")
    need = 3 if closed else 2
    if len(a) < need:
        raise ConfigError(f"{name}: strip has {len(a)} ruling(s), expected at least {need}")
    V = np.stack([a, b], axis=1).reshape(-1, 3)
    return Mesh(V, strip_faces(len(a), closed, twist), name=name)


def join_meshes(meshes, name: str = "meshes") -> Mesh:
    """Disjoint union of meshes (vertex blocks in the given order)."""
    meshes = list(meshes)
    if not meshes:
        raise ConfigError(f"{name}: nothing to join, expected at least one mesh")
    k = max(m.F.shape[1] for m in meshes)
    off = np.cumsum([0] + [m.n_vertices for m in meshes])
    F = [np.where(m.F >= 0, m.F + o, -1) for m, o in zip(meshes, off)]
    F = np.concatenate([np.pad(f, ((0, 0), (0, k - f.shape[1])), constant_values=-1) for f in F])
    return Mesh(np.concatenate([m.V for m in meshes]), F, name=name)


def strip_layouts(mesh: Mesh) -> list[StripLayout]:
    """The strips of ``mesh``, one :class:`StripLayout` per connected component.

    Raises MeshError when a component is not a single row of quads (a face
    that is not a quad, or a quad with more than two neighbours, or with two
    neighbours across adjacent edges).  The walk over the faces runs once per
    mesh.
    """
    t = mesh.topology
    if not np.all(mesh.face_sizes == 4):
        f = int(np.argmax(mesh.face_sizes != 4))
        raise MeshError(f"{mesh.name}: face {f} has {int(mesh.face_sizes[f])} vertices, "
                        "expected a strip of quads")
    F = mesh.F[:, :4]
    corners = t.offsets[:-1, None] + np.arange(4)[None, :]
    inner = ~t.is_boundary_edge[t.corner_edge[corners]]  # (m, 4): slot j edge x_j -> x_(j+1) shared
    count = inner.sum(axis=1)
    bad = (count > 2) | ((count == 2) & ~(inner[:, 0] & inner[:, 2]) & ~(inner[:, 1] & inner[:, 3]))
    if bad.any():
        f = int(np.argmax(bad))
        slots = np.nonzero(inner[f])[0].tolist()
        raise MeshError(f"{mesh.name}: face {f} has neighbours across slots {slots}, "
                        "expected a single row of quads (neighbours across opposite edges only)")
    edge_of = {(int(x), int(y)): int(e) for e, (x, y) in enumerate(t.edges)}
    face_comp = t.component[F[:, 0]]
    layouts = []
    for comp in np.unique(face_comp):  # one walk per strip
        faces = np.nonzero(face_comp == comp)[0]
        ends = faces[count[faces] < 2]
        closed = len(ends) == 0
        f0 = int(faces[0] if closed else ends[0])
        x = F[f0]
        j = int(np.argmax(inner[f0])) if count[f0] else 1
        A = [int(x[(j + 3) % 4]), int(x[j])]
        B = [int(x[(j + 2) % 4]), int(x[(j + 1) % 4])]
        order = [f0]
        f = f0
        while True:
            e = edge_of[(min(A[-1], B[-1]), max(A[-1], B[-1]))]
            nxt = [g for g in t.edge_faces[e] if g >= 0 and g != f]
            if not nxt or nxt[0] == f0:
                break
            f = int(nxt[0])
            x = F[f].tolist()
            ia, ib = x.index(A[-1]), x.index(B[-1])
            A.append(x[(2 * ia - ib) % 4])
            B.append(x[(2 * ib - ia) % 4])
            order.append(f)
        if closed:
            twist = (A[-1], B[-1]) == (B[0], A[0])
            A, B = A[:-1], B[:-1]
        else:
            twist = False
        if len(order) != len(faces):
            raise MeshError(f"{mesh.name}: the strip through face {f0} reaches {len(order)} of the "
                            f"{len(faces)} faces of its component, expected one row of quads")
        layouts.append(StripLayout(np.array(A), np.array(B), np.array(order), closed, twist))
    return layouts


def ruling_points(V: np.ndarray, layout: StripLayout) -> tuple[np.ndarray, np.ndarray]:
    """``(A, B)`` each ``(q + 1, 3)``: ruling ends in strip order, the first ruling repeated
    at the end of a closed strip (swapped for a half twist), so quad ``i`` is
    ``A[i], A[i+1], B[i+1], B[i]``."""
    A, B = V[layout.a], V[layout.b]
    if layout.closed:
        A, B = (np.concatenate([A, B[:1]]), np.concatenate([B, A[:1]])) if layout.twist else \
               (np.concatenate([A, A[:1]]), np.concatenate([B, B[:1]]))
    return A, B


def _refine_one(layout: StripLayout, n: int, degree: int) -> tuple[sp.csr_matrix, int]:
    """(2 r', n) operator for one strip (rows interleaved a'_i, b'_i) and r'."""
    r = layout.n_rulings
    if layout.twist:  # the boundary is one closed polyline a_0..a_(r-1), b_0..b_(r-1)
        loop = np.concatenate([layout.a, layout.b])
        C = curve_operator(2 * r, True, degree) @ _select(loop, n)
        half = C.shape[0] // 2
        Sa, Sb = C[:half], C[half:]
    else:
        C = curve_operator(r, layout.closed, degree)
        Sa, Sb = C @ _select(layout.a, n), C @ _select(layout.b, n)
    rf = Sa.shape[0]
    perm = np.argsort(np.concatenate([2 * np.arange(rf), 2 * np.arange(rf) + 1]))
    return sp.vstack([Sa, Sb], format="csr")[perm], rf


def _select(idx: np.ndarray, n: int) -> sp.csr_matrix:
    return sp.csr_matrix((np.ones(len(idx)), (np.arange(len(idx)), idx)), shape=(len(idx), n))


def refine_strips(mesh: Mesh, scheme: str = "chaikin", levels: int = 1) -> tuple[Mesh, sp.csr_matrix]:
    """Refine every strip of ``mesh`` by refining both boundary polylines.

    scheme : ``"chaikin"`` (degree 2) or ``"lane_riesenfeld"`` (cubic).
    Returns ``(fine, S)``: ``fine`` numbered strip by strip (``a_i = 2 i``,
    ``b_i = 2 i + 1`` within each block), ``S (n_fine, n)`` CSR with
    ``fine.V == S @ mesh.V``.  The ruling count doubles (open strips:
    ``2 r`` for Chaikin, ``2 r - 1`` for cubic; end rulings kept).
    A cylinder stays a cylinder and a cone a cone (rows of ``S`` sum to one).
    """
    if scheme not in CURVE_SCHEMES:
        raise ConfigError(f"strip refinement scheme {scheme!r} is unknown, expected one of "
                          f"{sorted(CURVE_SCHEMES)}")
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or levels < 0:
        raise ConfigError(f"strip refinement levels is {levels!r}, expected an integer >= 0")
    S = sp.identity(mesh.n_vertices, format="csr")
    fine = mesh
    for _ in range(levels):
        blocks, faces, off = [], [], 0
        for lay in strip_layouts(fine):
            Sk, rf = _refine_one(lay, fine.n_vertices, CURVE_SCHEMES[scheme])
            blocks.append(Sk)
            faces.append(strip_faces(rf, lay.closed, lay.twist) + off)
            off += 2 * rf
        S1 = sp.vstack(blocks, format="csr")
        fine = Mesh(S1 @ fine.V, np.concatenate(faces), name=mesh.name)
        S = (S1 @ S).tocsr()
    return fine, S
