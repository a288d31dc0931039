"""Analysis of PQ strips: rulings, singular curve, Gauss image, exact development.

For a strip (see :mod:`optimize.modelling.strips`) with quads ``Q_i = [a_i, a_(i+1),
b_(i+1), b_i]``, ``i = 0..q-1``, and ruling vectors ``u_i = b_i - a_i``:

- singular point ``r_i``: where the ruling lines ``a_i b_i`` and
  ``a_(i+1) b_(i+1)`` meet (the midpoint of their common perpendicular when
  they are skew; ``skew`` gives that distance, zero for a planar quad);
  the points ``r_i`` form the singular curve (edge of regression);
- kind of each quad: ``"cylindrical"`` (rulings parallel: ``r_i`` at
  infinity, NaN), ``"conical"`` (``r_i`` coincides with the singular point of
  a neighbouring quad: several rulings through one apex), ``"tangent"``
  (otherwise: a piece of a tangent developable);
- ``inside``: ``r_i`` lies on one of the two ruling segments of its quad
  (rulings cross within the designed patch, the quad folds over);
- Gauss image: the unit normal of each quad; for a PQ strip these form a
  curve on the sphere (each quad has one normal); ``spread`` measures the
  angle between a quad's corner normals and its normal (zero iff planar);
- development: the quads laid into the plane one after another, each
  rotated about the shared ruling, so edge lengths and angles are kept
  exactly for planar quads (the error is reported for the others).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..mesh import Mesh
from ..mesh.corners import angle_values
from ..tolerances import DEFAULT
from .strips import StripLayout, ruling_points, strip_layouts, strip_mesh

__all__ = ["StripAnalysis", "Development", "GaussImage", "analyze_strip", "develop", "gauss_image",
           "strip_report"]


@dataclass(frozen=True)
class StripAnalysis:
    """Rulings and singular curve of one strip (``q`` quads, ``q + 1`` rulings).

    rulings : (q + 1, 3) float, ``b_i - a_i`` (first ruling repeated on closed strips).
    singular_points : (q, 3) float, ``r_i`` (NaN rows for parallel rulings).
    t, s : (q,) float, parameters of ``r_i`` on ruling ``i`` (``a_i + t u_i``)
        and on ruling ``i + 1``; ``[0, 1]`` is the designed segment.
    skew : (q,) float, distance between the two ruling lines / mean ruling length.
    kinds : (q,) str, ``"cylindrical"`` | ``"conical"`` | ``"tangent"``.
    inside : (q,) bool, singular point on a ruling segment of its quad.
    pieces : list of (kind, first quad, last quad), maximal runs of one kind.
    kind : str, ``"cylinder"`` | ``"cone"`` (one apex) | ``"tangent"`` | ``"mixed"``.
    enters : bool, the singular curve enters the designed patch somewhere.
    """

    rulings: np.ndarray
    singular_points: np.ndarray
    t: np.ndarray
    s: np.ndarray
    skew: np.ndarray
    kinds: np.ndarray
    inside: np.ndarray
    pieces: list
    kind: str
    enters: bool

    def as_dict(self) -> dict:
        """JSON-ready summary (counts, worst skew, pieces)."""
        return {"quads": int(len(self.kinds)), "kind": self.kind, "enters_patch": self.enters,
                "max_skew": float(self.skew.max(initial=0.0)),
                "counts": {k: int(np.sum(self.kinds == k)) for k in ("cylindrical", "conical", "tangent")},
                "quads_with_singular_point_inside": np.nonzero(self.inside)[0].tolist(),
                "pieces": [list(p) for p in self.pieces]}


def _layout(mesh: Mesh, layout: StripLayout | None) -> StripLayout:
    return strip_layouts(mesh)[0] if layout is None else layout


def analyze_strip(mesh: Mesh, layout: StripLayout | None = None, *,
                  tol: float = DEFAULT.strip_parallel) -> StripAnalysis:
    """Rulings, singular points and the kind of every quad of one strip.

    mesh : Mesh, a strip (or several; ``layout`` picks one, default the first).
    tol : relative tolerance (``Tolerances.strip_parallel``) for parallel rulings (sine of their angle) and
        for coinciding apexes (distance / (ruling length + apex distance)).
    """
    lay = _layout(mesh, layout)
    A, B = ruling_points(mesh.V, lay)
    U = B - A
    u0, u1 = U[:-1], U[1:]
    w0 = A[:-1] - A[1:]
    aa = np.einsum("ij,ij->i", u0, u0)
    bb = np.einsum("ij,ij->i", u0, u1)
    cc = np.einsum("ij,ij->i", u1, u1)
    dd = np.einsum("ij,ij->i", u0, w0)
    ee = np.einsum("ij,ij->i", u1, w0)
    den = aa * cc - bb ** 2
    sine = np.linalg.norm(np.cross(u0, u1), axis=1) / np.sqrt(aa * cc)
    parallel = sine <= tol
    safe = np.where(parallel, 1.0, den)
    t = np.where(parallel, np.nan, (bb * ee - cc * dd) / safe)
    s = np.where(parallel, np.nan, (aa * ee - bb * dd) / safe)
    P = A[:-1] + t[:, None] * u0
    Q = A[1:] + s[:, None] * u1
    R = 0.5 * (P + Q)
    scale = np.sqrt(0.5 * (aa + cc))
    skew = np.where(parallel, 0.0, np.linalg.norm(P - Q, axis=1) / scale)  # parallel lines are coplanar
    # apexes shared with a neighbour (closed strips wrap around, not across a half twist's seam)
    q = len(R)
    nb = np.arange(q) + 1
    if lay.closed:
        nb %= q
    valid = (nb < q) & ~parallel & ~parallel[np.minimum(nb, q - 1)]
    nbc = np.minimum(nb, q - 1)
    size = scale + np.linalg.norm(R - A[:-1], axis=1)
    same = np.zeros(q, dtype=bool)
    same[valid] = (np.linalg.norm(R[valid] - R[nbc[valid]], axis=1)
                   <= tol * np.maximum(size[valid], size[nbc[valid]]))
    shared = same.copy()
    shared[nbc[same]] = True
    kinds = np.where(parallel, "cylindrical", np.where(shared | (q == 1), "conical", "tangent"))
    inside = ~parallel & (((t >= 0) & (t <= 1)) | ((s >= 0) & (s <= 1)))
    pieces = []
    start = 0
    for i in range(1, q + 1):  # runs over q quads, a summary
        if i == q or kinds[i] != kinds[start] or (kinds[i] == "conical" and not same[i - 1]):
            pieces.append((str(kinds[start]), start, i - 1))
            start = i
    if np.all(parallel):
        kind = "cylinder"
    elif np.all(kinds == "conical") and len(pieces) == 1:
        kind = "cone"
    elif np.all(kinds == "tangent"):
        kind = "tangent"
    else:
        kind = "mixed"
    return StripAnalysis(U, R, t, s, skew, kinds, inside, pieces, kind, bool(inside.any()))


@dataclass(frozen=True)
class GaussImage:
    """Gauss image of one strip.

    normals : (q, 3) float, unit quad normals in strip order (the curve on the sphere).
    spread : (q,) float, ``arcsin(max_k |c_k x n| / max_k |c_k|)`` (rad) for the corner
        cross products ``c_k`` and the unit normal ``n``: the angle between the
        lines of the corner normals and ``n``, each corner weighted by its
        area, so a degenerate corner counts for nothing; zero iff the quad is
        planar (a planar quad folded over is planar: :func:`analyze_strip`
        reports folds).
    turning : (q - 1,) float, angle between consecutive normals (rad).
    """

    normals: np.ndarray
    spread: np.ndarray
    turning: np.ndarray


def _quads(mesh: Mesh, lay: StripLayout) -> np.ndarray:
    A, B = ruling_points(mesh.V, lay)
    return np.stack([A[:-1], A[1:], B[1:], B[:-1]], axis=1)  # (q, 4, 3)


def gauss_image(mesh: Mesh, layout: StripLayout | None = None) -> GaussImage:
    """Normals of one strip's quads and how far each quad is from having a single normal."""
    lay = _layout(mesh, layout)
    Q = _quads(mesh, lay)
    N = np.cross(Q[:, 2] - Q[:, 0], Q[:, 3] - Q[:, 1])
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    C = np.cross(np.roll(Q, -1, axis=1) - Q, np.roll(Q, 1, axis=1) - Q)  # (q, 4, 3) corner normals
    size = np.linalg.norm(C, axis=2).max(axis=1)  # a degenerate corner (angle 0 or pi) weighs nothing
    sine = np.linalg.norm(np.cross(C, N[:, None, :]), axis=2).max(axis=1) / size
    spread = np.arcsin(np.minimum(sine, 1.0))
    turn = np.arctan2(np.linalg.norm(np.cross(N[:-1], N[1:]), axis=1), np.einsum("ij,ij->i", N[:-1], N[1:]))
    return GaussImage(N, spread, turn)


@dataclass(frozen=True)
class Development:
    """One strip unrolled into the plane (cut open at the seam of a closed strip).

    mesh : Mesh, the flat strip (z = 0), rulings ``a_i = 2 i``, ``b_i = 2 i + 1``, ``q + 1`` rulings.
    uv : (2 (q + 1), 2) float, the same points in the plane.
    vertex : (2 (q + 1),) int, the vertex of the 3D mesh each flat vertex comes from
        (seam vertices appear twice).
    edge_error : float, max |flat - 3D| length over edges and diagonals / mean edge length.
    angle_error : float, max |flat - 3D| corner angle (rad).
    """

    mesh: Mesh
    uv: np.ndarray
    vertex: np.ndarray
    edge_error: float
    angle_error: float


def develop(mesh: Mesh, layout: StripLayout | None = None) -> Development:
    """Unroll one strip into the plane, quad after quad about the shared rulings.

    Each quad is written in its own plane frame (origin ``a_i``, x along
    ``b_i - a_i``, normal by its diagonals); the frames are chained by the
    cumulative rotation and translation that carry ruling ``i + 1`` of quad
    ``i`` onto ruling ``i + 1`` of quad ``i + 1``.  Exact for planar quads.
    """
    lay = _layout(mesh, layout)
    Q = _quads(mesh, lay)  # (q, 4, 3): a_i, a_i+1, b_i+1, b_i
    q = len(Q)
    e1 = Q[:, 3] - Q[:, 0]
    L = np.linalg.norm(e1, axis=1)
    e1 /= L[:, None]
    n = np.cross(Q[:, 2] - Q[:, 0], Q[:, 3] - Q[:, 1])
    e2 = np.cross(n, e1)
    e2 /= np.linalg.norm(e2, axis=1, keepdims=True)
    rel = Q - Q[:, :1]
    loc = np.stack([np.einsum("qkj,qj->qk", rel, e1), np.einsum("qkj,qj->qk", rel, e2)], axis=2)  # (q, 4, 2)
    d = loc[:, 2] - loc[:, 1]
    theta = np.arctan2(d[:, 1], d[:, 0])
    phi = np.concatenate([[0.0], np.cumsum(theta)])  # frame angle of quad i (and one past the end)
    c, s = np.cos(phi[:-1]), np.sin(phi[:-1])
    o = loc[:, 1]
    step = np.stack([c * o[:, 0] - s * o[:, 1], s * o[:, 0] + c * o[:, 1]], axis=1)
    T = np.concatenate([np.zeros((1, 2)), np.cumsum(step, axis=0)])  # (q + 1, 2): flat a_i
    Lr = np.concatenate([L, [np.linalg.norm(d[-1])]])
    Bf = T + Lr[:, None] * np.stack([np.cos(phi), np.sin(phi)], axis=1)
    uv = np.stack([T, Bf], axis=1).reshape(-1, 2)
    flat = strip_mesh(np.c_[T, np.zeros(q + 1)], np.c_[Bf, np.zeros(q + 1)], name=f"{mesh.name}-flat")
    F2 = np.stack([T[:-1], T[1:], Bf[1:], Bf[:-1]], axis=1)  # (q, 4, 2)
    err_len = _quad_lengths(F2) - _quad_lengths(Q)
    h = _quad_lengths(Q)[:, :4].mean()
    ang_err = np.abs(_quad_angles(F2) - _quad_angles(Q)).max()
    A_idx, B_idx = lay.a, lay.b
    if lay.closed:
        A_idx, B_idx = (np.r_[A_idx, B_idx[0]], np.r_[B_idx, A_idx[0]]) if lay.twist else \
                       (np.r_[A_idx, A_idx[0]], np.r_[B_idx, B_idx[0]])
    vertex = np.stack([A_idx, B_idx], axis=1).ravel()
    return Development(flat, uv, vertex, float(np.abs(err_len).max() / h), float(ang_err))


def _quad_lengths(Q: np.ndarray) -> np.ndarray:
    """(q, 6) float: four edge lengths and two diagonals of quads ``Q (q, 4, d)``."""
    edges = np.linalg.norm(np.roll(Q, -1, axis=1) - Q, axis=2)
    diag = np.stack([np.linalg.norm(Q[:, 2] - Q[:, 0], axis=1), np.linalg.norm(Q[:, 3] - Q[:, 1], axis=1)], 1)
    return np.concatenate([edges, diag], axis=1)


def _quad_angles(Q: np.ndarray) -> np.ndarray:
    """(q, 4) float: corner angles of quads ``Q (q, 4, d)`` (unsigned)."""
    if Q.shape[2] == 2:
        Q = np.concatenate([Q, np.zeros(Q.shape[:2] + (1,))], axis=2)
    return angle_values(np.stack([Q, np.roll(Q, -1, axis=1), np.roll(Q, 1, axis=1)], axis=2))


def strip_report(mesh: Mesh, *, tol: float = DEFAULT.strip_parallel) -> list[dict]:
    """JSON-ready analysis of every strip of ``mesh``: kind, singular curve,
    Gauss-image spread, development errors, planarity."""
    from ..mesh.measures import planarity

    plan = planarity(mesh)
    out = []
    for i, lay in enumerate(strip_layouts(mesh)):
        rep = {"strip": i, "rulings": lay.n_rulings, "closed": lay.closed, "half_twist": lay.twist,
               "max_planarity": float(plan[lay.faces].max())}
        rep.update(analyze_strip(mesh, lay, tol=tol).as_dict())
        rep["max_gauss_spread_rad"] = float(gauss_image(mesh, lay).spread.max())
        dev = develop(mesh, lay)
        rep.update(development_edge_error=dev.edge_error, development_angle_error_rad=dev.angle_error)
        out.append(rep)
    return out
