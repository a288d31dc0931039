"""The unknowns, their starting values and the stacked constraints of one target.

Targets (all with auxiliary variables so every constraint is at most quadratic):

- ``pq``: vertices, unit face normals; planarity on every face.
- ``conical``: ``pq`` plus a unit axis and ``c = cos(theta)`` per interior
  valence-4 vertex (``terms.conical``) and the angle balance there
  (``terms.anglebalance``, which excludes degenerate cones).
- ``circular``: ``pq`` plus a centre and squared radius per quad
  (``terms.circular``) and the opposite-angle sums (``terms.anglesum``,
  which exclude crossed quads).

With ``unknowns="vertices"`` the same targets are written on the vertex
positions (auxiliary unknowns only for the few n-gons): planarity as the
signed distance between the diagonals of each quad (``terms.diagonals``;
an n-gon keeps a unit normal, ``terms.planarity`` on its corners), the
conical angle balance, the circular opposite-angle sums.  These rows are not quadratic, but the system is 3x smaller: for the
conical target the sparse factor of a 10,000-face mesh has 8.2 million
nonzeros instead of 23 million (the per-vertex cone axes and the angle rows
both couple whole vertex stars), and the optimizer converges in fewer
iterations (the axis unknowns of nearly cylindrical vertices are
ill-conditioned).  ``optimize_mesh`` uses it for ``conical`` by default
(``formulation="auto"``) and fits the node axes to the final face normals
(exact at a conical vertex, whose four normals lie on one circle).

Starting values come from the current mesh: face normals by Newell's method;
axes and ``c`` by the node-axis fit of :mod:`optimize.mesh.axes` to the four
unit normals (``n . X = 1`` in least squares, ``a = X / |X|``, ``c = 1 / |X|``;
the axis of the circle through them at a conical vertex); circle centres by a least-squares circle fit in the
best-fit plane of each quad.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import ConfigError
from ..mesh import Mesh
from ..mesh.axes import fit_star_axes
from ..mesh.measures import face_normals
from ..options import DEFAULT_TARGETS as TARGETS
from . import (
    anglebalance,
    anglesum,
    circular,
    conical,
    diagonals,
    nodeaxes,
    planarity,
    unit,
)
from .problem import UNKNOWNS, ProblemSpec, TermSpec, describe

ROWS = ("planarity", "unit", "diagonals", "conical", "anglebalance", "circular", "anglesum", "nodeaxes")
"""The term modules a Formulation evaluates; the description's other least-squares terms
(``glide``, ``edgefloor``, ``convexity``) need data the solver carries (the boundary curve,
the floors: ``solvers.guided.Glide``, ``Convex``)."""


def fit_axes(N: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Axes ``(p, 3)`` and ``c (p,)`` best fitting ``n . a = c`` for unit normals ``N (p, s, 3)``
    (:func:`optimize.mesh.axes.fit_star_axes`, the offset stage's fit)."""
    fit = fit_star_axes(N, np.ones(N.shape[:2], dtype=bool))
    return fit.axes, fit.cos_theta


def fit_circles(P: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centres ``(q, 3)`` and squared radii ``(q,)`` of circles fitted to ``P (q, 4, 3)``.

    The circle lies in the plane through the mean point with unit normal
    ``n (q, 3)``; algebraic least squares ``|p|^2 = 2 p.c + k`` in that plane.
    """
    o = P.mean(axis=1)
    helper = np.where((np.abs(n[:, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    e1 = np.cross(n, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(n, e1)
    d = P - o[:, None, :]
    u, v = np.einsum("qsj,qj->qs", d, e1), np.einsum("qsj,qj->qs", d, e2)
    M = np.stack([2 * u, 2 * v, np.ones_like(u)], axis=2)  # (q, 4, 3)
    rhs = u ** 2 + v ** 2
    MtM = np.einsum("qsi,qsj->qij", M, M) + 1e-12 * np.eye(3)
    sol = np.linalg.solve(MtM, np.einsum("qsi,qs->qi", M, rhs)[..., None])[..., 0]
    C = o + sol[:, :1] * e1 + sol[:, 1:2] * e2
    R = np.einsum("qsj,qsj->qs", P - C[:, None, :], P - C[:, None, :]).mean(axis=1)
    return C, R


class Formulation:
    """Layout, starting vector and constraint rows of ``target`` for the topology of ``mesh``.

    unknowns : ``"auxiliary"`` (vertices plus normals, axes, centres; every row
        at most quadratic) or ``"vertices"`` (positions only, see above).
    beams : node axes as unknowns with planar beams (conical, ``"vertices"`` only).
    spec : the problem description (:func:`optimize.terms.problem.describe`, method
        ``"default"``) to build from; when given, ``target``, ``unknowns`` and ``beams``
        are its.  ``mesh`` is the mesh the unknowns' ``vertices`` block lives on (the
        optimizer passes the normalized input: same faces and topology).

    The layout, the index sets and the list of rows (its least-squares terms of the
    modules ``ROWS``) are the description's; this class prepares what the rows need
    (diagonal quadruples, beam edges) and evaluates them.
    """

    def __init__(self, mesh: Mesh, target: str, unknowns: str = "auxiliary", beams: bool = False,
                 *, spec: ProblemSpec | None = None):
        if spec is None:
            if target not in TARGETS:
                raise ConfigError(f"target: {target!r} is not known, expected one of {TARGETS}")
            if unknowns not in UNKNOWNS:
                raise ConfigError(f"formulation: {unknowns!r} is not known, expected one of {UNKNOWNS}")
            if beams and unknowns == "auxiliary":
                raise ConfigError("torsion_free_beams: written for formulation 'vertices' only, not 'auxiliary'")
            spec = describe(mesh, target, "default", formulation=unknowns, beams=bool(beams))
        self.spec = spec
        self.mesh = mesh
        self.target = spec.target
        self.unknowns = spec.unknowns
        self.layout = spec.layout
        self.rows = tuple(t for t in spec.rows("least_squares") if t.module in ROWS)
        self.cone_vertices = spec.sets["cone_vertices"]
        self.quads = spec.sets["quads"]
        self.ngons = spec.sets["ngons"]
        self.axis_vertices = spec.sets["axis_vertices"]  # vertices with node-axis unknowns (beams)
        # cone vertices with an angle-balance row: all of them (self.angle_mask).  (Adding
        # rows only where a vertex is caught on the degenerate branch was tried: no reliable
        # detector was found before convergence, it flagged most vertices anyway.)
        self.angle_mask = np.ones(len(self.cone_vertices), dtype=bool)
        modules = {t.module for t in self.rows}
        if "diagonals" in modules:
            self.quadruples = diagonals.quadruples(mesh, max_size=4)
        if len(self.axis_vertices):
            self.beam_edges = nodeaxes.beam_edges(mesh)
            self.axis_row = np.full(mesh.n_vertices, -1, dtype=np.int64)
            self.axis_row[self.axis_vertices] = np.arange(len(self.axis_vertices))

    def start(self, V: np.ndarray) -> np.ndarray:
        """The starting unknown vector for positions ``V (n, 3)``."""
        if self.unknowns == "vertices":
            blocks = {"vertices": V}
            if len(self.ngons):
                blocks["ngon_normals"] = face_normals(self.mesh, V)[self.ngons]
            if len(self.axis_vertices):
                blocks["node_axes"], blocks["node_cos"] = nodeaxes.start(self.mesh, V, self.axis_vertices)
            return self.layout.pack(**blocks)
        N = face_normals(self.mesh, V)
        blocks = {"vertices": V, "normals": N}
        if self.target == "conical":
            blocks["axes"], blocks["cos"] = fit_axes(N[conical.cone_faces(self.mesh)])
        if self.target == "circular":
            Fq = self.mesh.F[self.quads, :4]
            blocks["centres"], blocks["radius2"] = fit_circles(V[Fq], N[self.quads])
        return self.layout.pack(**blocks)

    def terms(self, x: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
        """All constraint residuals ``(p,)`` stacked, and their Jacobian ``(p, layout.size)``."""
        r, J, wide = self.split_terms(x)
        return (np.concatenate([r] + [w[0] for w in wide]),
                sp.vstack([J] + [w[1] for w in wide], format="csr"))

    def split_terms(self, x: np.ndarray, exact_angles: bool = True):
        """``(r, J, wide)``: the compact-stencil constraints (each row within one face,
        or one vertex and its faces' normals) and the list of wide ones as
        ``(r_w, J_w, parts)`` with ``J_w = sum(parts)``, each part within one face
        (the angle balance of the auxiliary formulation couples a whole vertex star;
        with ``exact_angles`` it is among the compact rows instead).  The rows are the
        description's least-squares terms, in its order."""
        parts, wide = [], []
        for term in self.rows:
            if term.options.get("split") and not exact_angles:
                wide.append(self._rows(term, x, parts=True))
            else:
                parts.append(self._rows(term, x))
        return (np.concatenate([r for r, _ in parts]), sp.vstack([J for _, J in parts], format="csr"),
                wide)

    def _rows(self, term: TermSpec, x: np.ndarray, parts: bool = False):
        """``(r, J)`` of one of the description's terms at ``x`` (``parts``: the angle
        balance's per-corner Jacobians too)."""
        L, mesh, m, opt = self.layout, self.mesh, term.module, term.options
        if m == "planarity":
            faces = opt.get("faces")
            if faces is None:
                return planarity.terms(x, L, mesh)
            return planarity.terms(x, L, mesh, faces=self.spec.sets[faces], block=opt["block"])
        if m == "unit":
            return unit.terms(x, L, opt["block"])
        if m == "diagonals":
            return diagonals.terms(x, L, mesh, self.quadruples)
        if m == "conical":
            return conical.terms(x, L, mesh)
        if m == "anglebalance":
            if self.unknowns == "vertices":
                return anglebalance.terms(x, L, mesh)
            return anglebalance.terms(x, L, mesh, parts=parts, which=np.nonzero(self.angle_mask)[0])
        if m == "circular":
            return circular.terms(x, L, mesh)
        if m == "anglesum":
            return anglesum.terms(x, L, mesh)
        if m == "nodeaxes" and opt["part"] == "cone":
            return nodeaxes.cone_terms(x, L, mesh, self.axis_vertices)
        if m == "nodeaxes":
            return nodeaxes.beam_terms(x, L, self.beam_edges, self.axis_row)
        raise ValueError(f"term {term.name!r}: module {m!r} is not a row of the default method")

    def axis_defects(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """With node-axis unknowns: ``{"node_cone": |n . a - c| (r,), "beam": |(e x a_v) . a_w| / |e|
        (k,)}`` (both about radians: sines of the angles off the cone and off the beam plane)."""
        if not len(self.axis_vertices):
            return {}
        a = self.layout.view(x, "node_axes")
        unit_x = x.copy()
        self.layout.view(unit_x, "node_axes")[:] = a / np.linalg.norm(a, axis=1, keepdims=True)
        rc, _ = nodeaxes.cone_terms(unit_x, self.layout, self.mesh, self.axis_vertices, jacobian=False)
        rb, _ = nodeaxes.beam_terms(unit_x, self.layout, self.beam_edges, self.axis_row, jacobian=False)
        return {"node_cone": np.abs(rc), "beam": np.abs(rb)}

    def face_blocks(self) -> np.ndarray | None:
        """(m, b) int: per-face auxiliary unknowns (normal, and centre + radius for circular quads).

        Every constraint row touches at most one face's block, so the blocks of
        the normal matrix are independent ``b x b`` diagonal blocks: the
        ``"eliminate"`` solver removes them first (for conical the normals still
        couple to the vertex axes, which stay in the reduced system).
        """
        if self.unknowns == "vertices":
            return None
        N = self.layout.index("normals")
        if self.target in ("pq", "conical"):
            return N
        B = np.full((self.mesh.n_faces, 7), -1, dtype=np.int64)
        B[:, :3] = N
        B[self.quads, 3:6] = self.layout.index("centres")
        B[self.quads, 6] = self.layout.index("radius2")
        return B
