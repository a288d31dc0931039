"""Scale-free measures of a polygon mesh, all vectorized.

Definitions shared by the whole package (code, reports, tests):

- planarity of a quad: distance between its two diagonal lines divided by
  the mean diagonal length; of an n-gon (n > 4): max distance of a vertex from
  the least-squares plane divided by the mean edge length; triangles: 0;
- conical defect at an interior valence-4 vertex: ``|w1 + w3 - w2 - w4|``
  (radians), corner angles in cyclic order;
- circular defect of a quad: ``max(|phi1 + phi3 - pi|, |phi2 + phi4 - pi|)``;
- vertex type at interior valence-4 vertices (paper section 4): the sign of
  the signed area of the Gauss image (the spherical polygon of the face
  normals around the vertex) relative to the star orientation: elliptic (+),
  hyperbolic (-), parabolic (below tolerance);
- fairness: second differences ``a - 2 v + b`` along mesh polylines, divided
  by the mean edge length;
- folded face (of a result against its input): a face convex in the input
  with a reflex corner, a flipped normal or a collapsed edge in the result
  (:func:`folded_faces`);
- degenerate face, counted apart from folds (:func:`degenerate`): a shrunk
  edge (shorter than ``SHORT_EDGE`` of its face's longest edge, or in a
  result than ``SHRUNK`` of its input length) or a straight corner of a
  triangle or quad (its two edges on one line: ``|sine| <= STRAIGHT``, 180
  degrees or a 0 degree spike): either way the quad is a triangle.

Scale-free by construction: every function first scales the positions by a
power of two (exact, :func:`optimize.mesh.core.unit_exponent`) so that they lie in
[-1, 1]; ratios and angles are then the same bits as without scaling, and
neither overflow nor underflow for a mesh at 1e300 or 1e-300.  Lengths and
areas are scaled back at the end (an area beyond 1.8e308 is ``inf``: float64
cannot hold it).
"""
from __future__ import annotations

import numpy as np

from ..errors import MeshError
from ..tolerances import DEFAULT, Tolerances
from .core import Mesh, unit_exponent
from .corners import angle_values, corner_vertices


def _unit(V: np.ndarray) -> tuple[np.ndarray, int]:
    """(W, e): ``V`` scaled exactly into [-1, 1] (``V = W * 2**e``)."""
    e = unit_exponent(V)
    return (np.ldexp(V, -e) if e else V), e


def normalization(mesh: Mesh) -> tuple[np.ndarray, float]:
    """Centre ``(3,)`` and scale (mean edge length) that map ``mesh`` to unit edges: every solver
    works in these coordinates, so its weights mean the same at every scale."""
    return mesh.V.mean(axis=0), float(edge_lengths(mesh).mean())


def corner_angles(mesh: Mesh, V: np.ndarray | None = None) -> np.ndarray:
    """(c,) float: interior angle at every corner (radians), topology corner order (:mod:`optimize.mesh.corners`)."""
    V = _unit(mesh.V if V is None else V)[0]
    return angle_values(V[corner_vertices(mesh.topology)])


def quad_planarity(Q: np.ndarray) -> np.ndarray:
    """Planarity of quads ``Q (q, 4, 3)``: diagonal-line distance / mean diagonal length."""
    Q = _unit(Q)[0]
    d1 = Q[:, 2] - Q[:, 0]
    d2 = Q[:, 3] - Q[:, 1]
    n = np.cross(d1, d2)
    nn = np.linalg.norm(n, axis=1)
    l1, l2 = np.linalg.norm(d1, axis=1), np.linalg.norm(d2, axis=1)
    gap = Q[:, 1] - Q[:, 0]
    # parallel diagonals (a degenerate quad): fall back to point-line distance
    safe = nn > 1e-12 * l1 * l2
    dist = np.where(safe, np.abs(np.einsum("ij,ij->i", gap, n)) / np.where(safe, nn, 1.0),
                    np.linalg.norm(np.cross(gap, d1), axis=1) / np.maximum(l1, 1e-300))
    return dist / (0.5 * (l1 + l2))


def ngon_planarity(P: np.ndarray) -> np.ndarray:
    """Planarity of k-gons ``P (q, k, 3)``: max distance to the least-squares plane / mean edge length."""
    P = _unit(P)[0]
    c = P - P.mean(axis=1, keepdims=True)
    _, _, vt = np.linalg.svd(c, full_matrices=False)
    normal = vt[:, -1, :]
    dist = np.abs(np.einsum("qkj,qj->qk", c, normal)).max(axis=1)
    edge = np.linalg.norm(np.roll(P, -1, axis=1) - P, axis=2).mean(axis=1)
    return dist / edge


def planarity(mesh: Mesh, V: np.ndarray | None = None) -> np.ndarray:
    """(m,) float: planarity of every face (quads by diagonals, n-gons by plane fit)."""
    V = mesh.V if V is None else V
    sizes = mesh.face_sizes
    out = np.zeros(mesh.n_faces)
    q = sizes == 4
    if q.any():
        out[q] = quad_planarity(V[mesh.F[q, :4]])
    for k in np.unique(sizes[sizes > 4]):
        sel = sizes == k
        out[sel] = ngon_planarity(V[mesh.F[sel, :k]])
    return out


def conical_defect(mesh: Mesh, V: np.ndarray | None = None) -> np.ndarray:
    """(p,) float: ``|w1 + w3 - w2 - w4|`` at ``topology.interior_valence4`` vertices."""
    t = mesh.topology
    ang = corner_angles(mesh, V)
    w = ang[t.star_corners[t.interior_valence4, :4]]
    return np.abs(w[:, 0] - w[:, 1] + w[:, 2] - w[:, 3])


def circular_defect(mesh: Mesh, V: np.ndarray | None = None) -> np.ndarray:
    """(q,) float: ``max(|phi1 + phi3 - pi|, |phi2 + phi4 - pi|)`` for each quad face.

    Faces are those with ``face_sizes == 4`` in face order (``quad_faces``).
    """
    t = mesh.topology
    ang = corner_angles(mesh, V)
    quads = np.nonzero(mesh.face_sizes == 4)[0]
    phi = ang[t.offsets[quads][:, None] + np.arange(4)[None, :]]
    return np.maximum(np.abs(phi[:, 0] + phi[:, 2] - np.pi), np.abs(phi[:, 1] + phi[:, 3] - np.pi))


def face_normals(mesh: Mesh, V: np.ndarray | None = None) -> np.ndarray:
    """(m, 3) float: unit face normals (Newell's method, orientation of the face order)."""
    n = _scaled_areas(mesh, V)[0]
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def _vector_areas(mesh: Mesh, V: np.ndarray | None = None) -> np.ndarray:
    """(m, 3) float: twice the vector area of each face (Newell), taken about the face's
    first vertex so that far-from-origin coordinates lose no precision."""
    n, e = _scaled_areas(mesh, V)
    return np.ldexp(n, 2 * e) if e else n


def _scaled_areas(mesh: Mesh, V: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """(A, e): :func:`_vector_areas` of the positions scaled into [-1, 1], area unit ``4**e``."""
    V, e = _unit(mesh.V if V is None else V)
    t = mesh.topology
    o = V[mesh.F[t.corner_face, 0]]
    cr = np.cross(V[t.corner_vertex] - o, V[t.corner_next_vertex] - o)
    n = np.zeros((mesh.n_faces, 3))
    np.add.at(n, t.corner_face, cr)
    return n, e


COLLAPSED = 1e-3  # an edge shorter than this fraction of its start length has collapsed


def corner_turns(mesh: Mesh, V: np.ndarray | None = None, normals: np.ndarray | None = None) -> np.ndarray:
    """(c,) float: signed sine of each corner angle about its face's normal (Newell):
    positive at a convex corner, negative at a reflex one (topology corner order).
    ``normals (m, 3)``: the face normals at ``V`` when the caller has them already."""
    V = _unit(mesh.V if V is None else V)[0]
    t = mesh.topology
    P = V[t.corner_vertex]
    u, w = V[t.corner_next_vertex] - P, V[t.corner_prev_vertex] - P
    N = (face_normals(mesh, V) if normals is None else normals)[t.corner_face]
    lengths = np.maximum(np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1), 1e-300)
    return np.einsum("ij,ij->i", np.cross(u, w), N) / lengths


def folded_faces(mesh: Mesh, V: np.ndarray, V0: np.ndarray | None = None,
                 tol: float = DEFAULT.fold) -> np.ndarray:
    """(m,) bool: faces that folded going from positions ``V0 (n, 3)`` (default ``mesh.V``)
    to ``V (n, 3)``: a corner convex at ``V0`` turned reflex (signed sine below ``-tol``,
    ``Tolerances.fold``),
    the face normal turned by more than 90 degrees, or an edge shrank below
    ``COLLAPSED`` of its length at ``V0`` (a vertex slid onto its neighbour: the quad is
    a triangle now).  A planar bow-tie, a dented or a collapsed panel is planar but
    cannot be cut from glass, so the optimizer reports it."""
    V0 = mesh.V if V0 is None else V0
    t = mesh.topology
    N0, N1 = face_normals(mesh, V0), face_normals(mesh, V)
    before, after = corner_turns(mesh, V0, N0), corner_turns(mesh, V, N1)
    bad = np.zeros(mesh.n_faces, dtype=bool)
    np.logical_or.at(bad, t.corner_face, (before > -tol) & (after < -tol))
    nxt = t.corner_next_vertex
    e = max(unit_exponent(V0), unit_exponent(V))  # one scale for both: the lengths are compared
    W0, W1 = np.ldexp(V0, -e), np.ldexp(V, -e)
    l0 = np.linalg.norm(W0[nxt] - W0[t.corner_vertex], axis=1)
    l1 = np.linalg.norm(W1[nxt] - W1[t.corner_vertex], axis=1)
    np.logical_or.at(bad, t.corner_face, l1 < COLLAPSED * l0)
    flipped = np.einsum("ij,ij->i", N0, N1) < 0
    return bad | flipped


SHORT_EDGE = 1e-6
"""A face side shorter than this fraction of the longest side of its face has shrunk: the face
lost a corner (a quad with one is a triangle; a 1 m panel with a 1 um side)."""
SHRUNK = 1e-2
"""A side of a result shorter than this fraction of its length in the input has shrunk (a vertex
slid toward its neighbour; below ``COLLAPSED`` the face also counts as folded)."""
STRAIGHT = 1e-6
"""A corner whose sine (:func:`corner_turns`) is at most this in size is straight (the default
``Tolerances.fold``, about 6e-5 degrees: inside it a corner is neither convex nor folded).  Fixed,
not the run's fold tolerance: a fold tolerance loosened to let dents pass does not make a
corner of 60 degrees straight."""


def shrunk_edges(mesh: Mesh, V: np.ndarray | None = None, V0: np.ndarray | None = None) -> np.ndarray:
    """(c,) bool, topology corner order: the face side from each corner to the next is shorter
    than ``SHORT_EDGE`` x the longest side of its face at ``V (n, 3)`` (default ``mesh.V``), or,
    given start positions ``V0 (n, 3)``, than ``SHRUNK`` x its length at ``V0``."""
    V = mesh.V if V is None else V
    t = mesh.topology
    e = unit_exponent(V) if V0 is None else max(unit_exponent(V), unit_exponent(V0))  # one scale: compared
    W = np.ldexp(V, -e)
    side = np.linalg.norm(W[t.corner_next_vertex] - W[t.corner_vertex], axis=1)
    longest = np.zeros(mesh.n_faces)
    np.maximum.at(longest, t.corner_face, side)
    bad = side < SHORT_EDGE * longest[t.corner_face]
    if V0 is not None:
        W0 = np.ldexp(V0, -e)
        bad |= side < SHRUNK * np.linalg.norm(W0[t.corner_next_vertex] - W0[t.corner_vertex], axis=1)
    return bad


def straight_corners(mesh: Mesh, V: np.ndarray | None = None, tol: float = STRAIGHT) -> np.ndarray:
    """(c,) bool, topology corner order: corners of triangles and quads whose two sides lie on one
    line, ``|corner_turns| <= tol`` (``STRAIGHT``): 180 degrees (the quad is a triangle with a
    vertex on a side) or a 0 degree spike.  Inside the fold tolerance, so never folded, yet no
    panel.  Corners of larger polygons are left alone (a vertex on a side of a cap is
    allowed)."""
    t = mesh.topology
    return (np.abs(corner_turns(mesh, V)) <= tol) & (mesh.face_sizes[t.corner_face] <= 4)


def degenerate(mesh: Mesh, V: np.ndarray | None = None, V0: np.ndarray | None = None,
               tol: float = STRAIGHT) -> dict:
    """The degenerate faces of ``mesh`` at ``V (n, 3)`` (default ``mesh.V``; ``V0 (n, 3)``: the
    input positions of a result, for shrinking) as JSON-ready entries, apart from folds:

    ``{"shrunk_edges": {"count": faces, "edges": mesh edges, "faces": first 20},
    "straight_corners": {"count": faces, "corners": corners, "faces": first 20}}``
    (:func:`shrunk_edges`, :func:`straight_corners`)."""
    t = mesh.topology
    short, straight = shrunk_edges(mesh, V, V0), straight_corners(mesh, V, tol)
    out = {}
    for key, bad, what, n in (("shrunk_edges", short, "edges", np.unique(t.corner_edge[short]).size),
                              ("straight_corners", straight, "corners", int(straight.sum()))):
        faces = np.unique(t.corner_face[bad])
        out[key] = {"count": int(faces.size), what: int(n), "faces": faces[:20].tolist()}
    return out


#: Largest coordinate (in the mesh's units) taken: squared lengths, areas and their sums of larger
#: coordinates overflow float64 (largest 1.8e308).
MAX_COORDINATE = 1e150


def range_problem(V: np.ndarray, resolution: float | None = None, unit: str = "mm",
                  needs: str = "") -> str | None:
    """Why positions ``V (..., 3)`` are out of range, or None: a coordinate beyond
    ``MAX_COORDINATE``, or (``resolution`` given, in ``unit``) one so large that float64 holds it
    more coarsely than ``resolution`` (``needs``: what needs it, for the sentence)."""
    top = float(np.abs(V).max(initial=0.0))
    if top > MAX_COORDINATE:
        return (f"coordinates up to {top:.3g} {unit}: their squared lengths and areas overflow float64 "
                f"(largest {np.finfo(float).max:.2g}); expected |x| <= {MAX_COORDINATE:.0e} {unit} (is the unit "
                "right?)")
    if resolution is not None and np.spacing(top) > resolution:
        limit = resolution / np.finfo(float).eps
        return (f"coordinates up to {top:.3g} {unit}: float64 holds them only to {np.spacing(top):.3g} {unit}, "
                f"coarser than {needs + ' ' if needs else ''}{resolution:g} {unit}; expected |x| < {limit:.2g} "
                f"{unit} (is the unit right? else move the design near the origin)")
    return None


def check_range(mesh: Mesh, where: str, resolution: float | None = None, unit: str = "mm",
                needs: str = "") -> None:
    """Raise :class:`MeshError` ``"where: ..."`` when :func:`range_problem` finds one."""
    why = range_problem(mesh.V, resolution, unit, needs)
    if why:
        raise MeshError(f"{where}: {why}")


def relative_resolution(mesh: Mesh, V: np.ndarray | None = None) -> float:
    """The float64 spacing at the largest coordinate of ``V (n, 3)`` (default ``mesh.V``) over the
    mean edge length: below about this no relative measure (planarity ...) of the stored
    positions can go (a mesh 1e14 mm from the origin with 1 m edges: 1.6e-5)."""
    V = mesh.V if V is None else V
    W, k = _unit(V)
    e = mesh.topology.edges
    mean = float(np.linalg.norm(W[e[:, 1]] - W[e[:, 0]], axis=1).mean())
    top = float(np.abs(V).max(initial=0.0))
    return float(np.spacing(top) / np.ldexp(mean, k)) if mean > 0 else float("inf")


def face_areas(mesh: Mesh, V: np.ndarray | None = None) -> np.ndarray:
    """(m,) float: vector area of each face (exact for planar faces)."""
    n, e = _scaled_areas(mesh, V)
    with np.errstate(over="ignore"):  # an area beyond float64 is inf
        return np.ldexp(0.5 * np.linalg.norm(n, axis=1), 2 * e)


def gauss_image_area(mesh: Mesh, V: np.ndarray | None = None) -> np.ndarray:
    """(p,) float: signed spherical area of the face normals around interior valence-4 vertices.

    Positive when the normals turn the same way as the star (elliptic), negative
    for hyperbolic vertices.  Computed as a fan of spherical triangles from the
    mean normal (Van Oosterom-Strackee formula).
    """
    t = mesh.topology
    N = face_normals(mesh, V)[t.star_faces[t.interior_valence4, :4]]  # (p, 4, 3)
    c = N.sum(axis=1)
    c /= np.maximum(np.linalg.norm(c, axis=1, keepdims=True), 1e-300)
    a, b = N, np.roll(N, -1, axis=1)
    cc = np.broadcast_to(c[:, None, :], a.shape)
    num = np.einsum("pij,pij->pi", cc, np.cross(a, b))
    den = 1 + np.einsum("pij,pij->pi", a, b) + np.einsum("pij,pij->pi", b, cc) + np.einsum("pij,pij->pi", cc, a)
    return (2 * np.arctan2(num, den)).sum(axis=1)


def vertex_types(mesh: Mesh, V: np.ndarray | None = None, tol: float = 1e-9) -> np.ndarray:
    """(p,) str: 'elliptic', 'hyperbolic' or 'parabolic' at interior valence-4 vertices.

    tol : steradians; a Gauss image area with ``|area| <= tol`` is parabolic.  The
        area is already scale-free, so the threshold is absolute (a threshold
        relative to the largest area would classify round-off on a cylinder).
    """
    area = gauss_image_area(mesh, V)
    kinds = np.where(area > tol, "elliptic", np.where(area < -tol, "hyperbolic", "parabolic"))
    return kinds


def edge_lengths(mesh: Mesh, V: np.ndarray | None = None) -> np.ndarray:
    """(e,) float: length of every edge."""
    W, k = _unit(mesh.V if V is None else V)
    e = mesh.topology.edges
    return np.ldexp(np.linalg.norm(W[e[:, 1]] - W[e[:, 0]], axis=1), k)


def fairness(mesh: Mesh, V: np.ndarray | None = None) -> np.ndarray:
    """(t,) float: ``|a - 2 v + b|`` / mean edge length along mesh polylines."""
    V = _unit(mesh.V if V is None else V)[0]
    T = mesh.topology.fair_triples
    d = V[T[:, 0]] - 2 * V[T[:, 1]] + V[T[:, 2]]
    return np.linalg.norm(d, axis=1) / edge_lengths(mesh, V).mean()


def _stats(x: np.ndarray, tol: float | None = None) -> dict:
    out = {"count": int(x.size)}
    if x.size:
        out.update(max=float(x.max()), mean=float(x.mean()), worst=int(np.argmax(x)))
    else:
        out.update(max=0.0, mean=0.0, worst=None)
    if tol is not None:
        out.update(tolerance=tol, ok=bool(out["max"] <= tol))
    return out


def summary(mesh: Mesh, tol: Tolerances = DEFAULT) -> dict:
    """Every measure of ``mesh`` as a JSON-ready dict (the output of ``fabricate measure``)."""
    t = mesh.topology
    plan = planarity(mesh)
    con = conical_defect(mesh)
    cir = circular_defect(mesh)
    ang = corner_angles(mesh)
    W, k = _unit(mesh.V)  # lengths and areas: statistics in [-1, 1], scaled back once (no overflow
    el = edge_lengths(mesh, W)  # of a sum of finite values; an area beyond float64 is inf)
    area = face_areas(mesh, W)
    with np.errstate(over="ignore"):
        diagonal = mesh.bbox_diagonal()
        lengths = {s: float(np.ldexp(getattr(el, s)(), k)) for s in ("min", "max", "mean")}
        areas = {s: float(np.ldexp(getattr(area, s)(), 2 * k)) for s in ("min", "max", "mean")}
    kinds = vertex_types(mesh)
    fair = fairness(mesh)
    con_s = _stats(con, tol.conical)
    if con.size:
        con_s["worst"] = int(t.interior_valence4[con_s["worst"]])
    cir_s = _stats(cir, tol.circular)
    if cir.size:
        cir_s["worst"] = int(np.nonzero(mesh.face_sizes == 4)[0][cir_s["worst"]])
    sizes = np.bincount(mesh.face_sizes)
    return {
        "mesh": {
            "name": mesh.name, "vertices": mesh.n_vertices, "faces": mesh.n_faces,
            "face_sizes": {str(k): int(c) for k, c in enumerate(sizes) if c},
            "edges": int(len(t.edges)), "boundary_loops": len(t.boundary_loops),
            "components": t.n_components, "orientable": t.orientable,
            "irregular_vertices": int(t.interior_irregular.size),
            "bbox_diagonal": diagonal,
        },
        "planarity": _stats(plan, tol.planarity),
        "conical": con_s,
        "circular": cir_s,
        "vertex_types": {k: int(np.sum(kinds == k)) for k in ("elliptic", "hyperbolic", "parabolic")},
        "fairness": _stats(fair),
        "edge_length": lengths,
        "angle_deg": {"min": float(np.degrees(ang.min())), "max": float(np.degrees(ang.max())),
                      "mean": float(np.degrees(ang.mean()))},
        "face_area": areas,
        **degenerate(mesh),
    }
