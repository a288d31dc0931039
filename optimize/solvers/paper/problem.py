"""The data of one run of the paper's methods, shared by penalty, SQP and hybrid.

What the run solves comes from its problem description
(:class:`optimize.terms.problem.ProblemSpec`, :func:`~optimize.terms.problem.describe`,
the default method's too): the layout, the normalization, the fixed vertices, the
rows and the energies.  Named variable layout (:class:`optimize.terms.variables.Layout`, the default
method's): the unknown vector has one block, ``vertices (n, 3)``, the vertex
positions centred at their mean ``c``, divided by the mean edge length ``h``
(:func:`optimize.mesh.measures.normalization`, the default method's
normalization) and turned to the input's canonical axes ``R``
(:func:`optimize.solvers.paper.frame.canonical_rotation`): ``x = ((V - c) / h) R``.
Every residual and step is scale-free (angles and determinants do not change,
fairness is ``K x`` and closeness ``(x - y) . n`` with footpoints and normals on the
reference in the same coordinates), and a rigid motion or a uniform scale of the
input changes the solver's input by rounding only: the methods move with their input
(the penalty method's per-coordinate damping would not, in the model's axes).
Fixed vertices are removed: Jacobians are restricted to the ``free``
coordinates and steps are scattered back with :meth:`Problem.step`.

Everything that does not change during a run is prepared once here: the
constraint systems' sparsity patterns, the pattern :attr:`Problem.hpat` of
the objective's Hessian ``w1 K^T K + w2 C^T C``, the banded layouts of the
solvers (:meth:`Problem.band`), and the closest-point search, which keeps
each vertex's candidate triangles between iterations
(:class:`optimize.proximity.Footpoints`, exact).  Problems are kept per input mesh
for repeated runs (:mod:`optimize.solvers.paper.cache`).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import shortest_path

from ... import kernels
from ...mesh import Mesh, measures
from ...mesh.axes import fit_axes
from ...mesh.corners import angle_values, corner_vertices
from ...options import DEFAULTS
from ...proximity.footpoints import Footpoints
from ...proximity.surface import Reference
from ...mesh.conjugacy import record_net
from ...result import OptimizeResult, check_folds, record_shape
from ...terms.closeness import closeness_residual
from ...terms.determinants import det_values
from ...terms.fairness import fairness_matrix
from ...terms.problem import ProblemSpec, describe
from ...tolerances import DEFAULT, Tolerances
from .frame import canonical_rotation
from .system import ConstraintSystem, Pattern
from .targets import prepare_all

FOOT_MARGIN = 0.3  # footpoint candidates are renewed for vertices that moved this many mean edges (x units)


class Problem:
    """Constraint blocks, energies, measures and the result of one run.

    Parameters
    ----------
    mesh : Mesh, the input (never modified).
    target : "pq" | "conical" | "circular" | "strip".
    reference : Mesh or None, surface for closeness and ``max_distance`` (default: ``mesh``).
    fixed : None | "boundary" | "corners" | (k,) int vertex indices that do not move.
    fairness, closeness : initial weights ``w1, w2`` of ``f_fair`` and ``f_close``.
    tol : Tolerances of the tested defects.
    mu : weight of the determinant terms (default
        :func:`optimize.terms.problem.default_mu` of ``method``).
    method : "penalty" (its rows only), "sqp" (its constraints only) or "hybrid" (both).
    spec : the description (:func:`optimize.terms.problem.describe`) to build from;
        when given, ``target``, ``reference``, ``fixed``, the weights, ``mu`` and
        ``method`` are taken from it.

    The layout, normalization, fixed set, rows and energies are the description's
    (:attr:`spec`); the penalty rows :attr:`terms` are its least-squares terms, SQP's
    :attr:`sqp_terms` its constraints, prepared by
    :func:`optimize.solvers.paper.targets.prepare_all`.
    """

    def __init__(self, mesh: Mesh, target: str = "pq", *, reference: Mesh | None = None, fixed=None,
                 fairness: float = DEFAULTS.fairness, closeness: float = DEFAULTS.closeness, tol: Tolerances = DEFAULT,
                 mu: float | None = None, method: str = "hybrid", spec: ProblemSpec | None = None):
        if spec is None:
            spec = describe(mesh, target, method, fixed=fixed, fairness=fairness, closeness=closeness,
                            reference=reference, mu=mu)
        self.spec = spec
        self.mesh, self.target, self.tol = spec.mesh, spec.target, tol
        mesh = spec.mesh
        self.terms = prepare_all(spec, "least_squares")
        self.sqp_terms = prepare_all(spec, "constraint")
        self.tests = spec.tests
        self.w_fair, self.w_close = spec.energies.fairness, spec.energies.closeness
        self.center, self.h = spec.centre, spec.scale
        self.R = canonical_rotation((mesh.V - self.center) / self.h)  # (3, 3), columns: the axes
        self.layout = spec.layout  # x = ((V - center) / h) R, named
        self.fixed = spec.fixed
        mask = np.ones(self.layout.size, dtype=bool)
        mask[self.layout.index("vertices")[self.fixed].ravel()] = False
        self.free = np.nonzero(mask)[0]
        self._all_free = len(self.free) == self.layout.size
        self.K_full = fairness_matrix(mesh)  # (3t, 3n)
        self.K = self._cols(self.K_full)  # (3t, k) on the free coordinates
        self._systems = {}
        self.vid = corner_vertices(mesh.topology).astype(np.int64)  # (c, 3) corner, next, previous vertex
        self.quads = np.ascontiguousarray(mesh.F[mesh.face_sizes == 4, :4], dtype=np.int64)  # (q, 4)
        self._close = None  # the closeness Jacobian's pattern, built when asked for
        self._hessian_pattern()
        self.reference = mesh if spec.energies.reference is None else spec.energies.reference
        self._ref = self._foot = None
        self.has_quads = bool(np.any(mesh.face_sizes == 4))
        self._quads_only = bool(np.all(mesh.face_sizes <= 4))  # planarity: quads (triangles count 0)
        self._bands = {}

    def _hessian_pattern(self) -> None:
        """The fixed pattern ``hpat`` of ``w1 K^T K + w2 C^T C`` (and the diagonal) on the free coordinates."""
        k = len(self.free)
        colmap = np.full(self.layout.size, -1, dtype=np.int64)
        colmap[self.free] = np.arange(k)
        cc = colmap[self.layout.index("vertices")]  # (n, 3) free column of each coordinate
        self._cv = np.nonzero(cc[:, 0] >= 0)[0]  # vertices with free coordinates (all three)
        cc = cc[self._cv]  # (f, 3)
        KtK = (self.K.T @ self.K).tocoo()
        self.Kt = self.K.T.tocsr()  # (k, 3t)
        rows = np.concatenate([KtK.row, np.repeat(cc, 3, axis=1).ravel(), np.arange(k)])
        cols = np.concatenate([KtK.col, np.tile(cc, (1, 3)).ravel(), np.arange(k)])
        self.hpat = Pattern(rows, cols, (k, k))
        nk, nc = len(KtK.data), 9 * len(cc)
        self._h_fair = self.hpat.data(np.concatenate([KtK.data, np.zeros(nc + k)]))
        self._h_close = self.hpat.inv[nk:nk + nc]  # distinct positions

    def hessian_data(self, w1: float, w2: float, N: np.ndarray | None) -> np.ndarray:
        """Values on :attr:`hpat` of ``w1 K^T K + w2 C^T C`` (closeness rows with unit normals ``N (n, 3)``)."""
        out = w1 * self._h_fair
        if w2 > 0:
            Nf = N[self._cv]
            out[self._h_close] += w2 * np.einsum("ia,ib->iab", Nf, Nf).ravel()
        return out

    def unknown_levels(self) -> np.ndarray:
        """(k,) float: for every free coordinate, its vertex's distance (in edges) from a
        peripheral vertex of the mesh: ordering by it lays a strip out along its length
        (folded where it closes), a candidate for the banded solvers' ordering."""
        if "levels" in self._bands:
            return self._bands["levels"]
        e = self.mesh.topology.edges
        n = self.mesh.n_vertices
        G = sp.csr_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
        G = G + G.T
        d = shortest_path(G, unweighted=True, indices=0)
        far = int(np.argmax(np.where(np.isfinite(d), d, -1.0)))
        d = shortest_path(G, unweighted=True, indices=far)
        d = np.where(np.isfinite(d), d, n)  # other components after this one
        self._bands["levels"] = d[self.free // 3]
        return self._bands["levels"]

    def band(self, name: str, factory):
        """A banded layout kept for the run (``factory(problem)`` on first use; None = not banded)."""
        if name not in self._bands:
            self._bands[name] = factory(self)
        return self._bands[name]

    @property
    def system(self) -> ConstraintSystem:
        """The penalty method's constraint rows (:attr:`terms`), built on first use."""
        return self._system("penalty", self.terms)

    @property
    def sqp_system(self) -> ConstraintSystem:
        """SQP's constraint rows (:attr:`sqp_terms`), built on first use."""
        return self._system("sqp", self.sqp_terms)

    def _system(self, name: str, terms: list) -> ConstraintSystem:
        if name not in self._systems:
            self._systems[name] = ConstraintSystem(self.mesh, terms, None if self._all_free else self.free,
                                                   self.layout)
        return self._systems[name]

    # -- variables ----------------------------------------------------------
    @property
    def ref(self) -> Reference:
        """The closest-point structure of the reference in the unknowns' coordinates
        (:meth:`scaled`; built on first use)."""
        if self._ref is None:
            self._ref = Reference(self.reference.with_vertices(self.scaled(self.reference.V)))
        return self._ref

    def scaled(self, V: np.ndarray) -> np.ndarray:
        """(n, 3) float: model positions ``V (n, 3)`` in the unknowns' coordinates ``((V - c) / h) R``."""
        return ((np.asarray(V, dtype=np.float64) - self.center) / self.h) @ self.R

    def x0(self) -> np.ndarray:
        """(3 n,) float: the scaled input positions."""
        return self.layout.pack(vertices=self.scaled(self.mesh.V))

    def vertices(self, x: np.ndarray) -> np.ndarray:
        """(n, 3) float: the ``vertices`` block of ``x`` (scaled positions; a view)."""
        return self.layout.view(x, "vertices")

    def positions(self, x: np.ndarray) -> np.ndarray:
        """(n, 3) float: model positions of the scaled vector ``x (3 n,)``."""
        return self.center + self.h * (self.vertices(x) @ self.R.T)

    def step(self, x: np.ndarray, s: np.ndarray, alpha: float = 1.0) -> np.ndarray:
        """(3 n,) float: ``x`` moved by ``alpha * s`` on the free coordinates (``s (k,)``)."""
        out = x.copy()
        out[self.free] += alpha * s
        return out

    def _cols(self, J: sp.spmatrix) -> sp.csr_matrix:
        J = sp.csr_matrix(J)
        return J if self._all_free else J[:, self.free]

    def cols2(self, H: sp.spmatrix) -> sp.csr_matrix:
        """A ``(3 n, 3 n)`` matrix restricted to the free coordinates, ``(k, k)``."""
        H = sp.csr_matrix(H)
        return H if self._all_free else H[self.free][:, self.free]

    # -- rows ---------------------------------------------------------------
    def constraints(self, x: np.ndarray, weighted: bool = False, jac: bool = True, sqp: bool = False):
        """Stacked constraint rows at ``x``.

        Returns ``c (r,)``, ``A (r, k)`` csr on the free coordinates and
        ``blocks`` (dict name -> slice of the rows); only ``c`` without ``jac``.
        With ``weighted`` each block is multiplied by ``sqrt(weight)`` (the
        penalty energy's rows).  ``sqp`` selects SQP's rows
        (the description's constraints, :func:`optimize.terms.problem.describe`).
        """
        system = self.sqp_system if sqp else self.system
        out = system.evaluate(self.vertices(x), jac=jac, weighted=weighted)
        return (*out, system.blocks) if jac else out

    def fairness(self, x: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
        """Unweighted fairness rows ``(K x (3t,), K (3t, k))`` in mean-edge units."""
        return kernels.matvec(self.K_full, x), self.K

    def reset_warm_start(self) -> None:
        """Before a run on a reused problem: the closest-point search starts afresh (its structure kept)."""
        if self._foot is not None:
            self._foot.reset()

    @property
    def foot_search(self) -> Footpoints:
        """Exact closest points with candidates kept between iterations (built on first use)."""
        if self._foot is None:
            self._foot = Footpoints(self.ref, FOOT_MARGIN)
        return self._foot

    def footpoints(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Closest points ``Y (n, 3)`` and unit normals ``N (n, 3)`` on the reference, both in the
        unknowns' coordinates (:meth:`scaled`)."""
        return self.foot_search.closest(self.vertices(x))

    def closeness(self, x: np.ndarray, foot=None, jac: bool = True):
        """Unweighted tangent-plane closeness rows ``(r (n,), J (n, k))`` at footpoints ``foot``.

        ``foot = (Y, N)`` from :meth:`footpoints` (recomputed at ``x`` when None).  The rows
        are :func:`optimize.terms.closeness.closeness_terms`'s in the unknowns' coordinates (``J``
        the same matrix, on the free columns, its values set on a pattern built once).
        """
        Y, N = self.footpoints(x) if foot is None else foot
        r = closeness_residual(self.vertices(x), Y, N)
        if not jac:
            return r
        if self._close is None:
            n = self.mesh.n_vertices
            self._close = Pattern(np.repeat(np.arange(n), 3), np.arange(3 * n), (n, 3 * n),
                                  None if self._all_free else self.free)
        return r, self._close.matrix(N)

    def least_squares(self, x: np.ndarray, w1: float, w2: float, foot=None, grad: bool = True):
        """``w1 |K x|^2 + w2 |r_close|^2`` at ``x`` and, with ``grad``, half its gradient ``(k,)``
        ``w1 K^T K x + w2 C^T r_close`` (footpoints ``foot`` fixed; weights 0 leave a term out)."""
        f = 0.0
        g = np.zeros(len(self.free)) if grad else None
        if w1 > 0:
            r = kernels.matvec(self.K_full, x)
            f += w1 * float(r @ r)
            if grad:
                g += w1 * kernels.matvec(self.Kt, r)
        if w2 > 0:
            Y, N = self.footpoints(x) if foot is None else foot
            r = closeness_residual(self.vertices(x), Y, N)
            f += w2 * float(r @ r)
            if grad:
                G = N * r[:, None]
                g += w2 * (G.ravel() if self._all_free else G.ravel()[self.free])
        return (f, g) if grad else f

    # -- measures and result ------------------------------------------------
    def measure(self, x: np.ndarray) -> dict:
        """Max defects at ``x``: planarity, conical, circular, det (quads), fairness energy."""
        Vs = self.vertices(x)  # every measure is scale-free: the scaled positions will do
        t = self.mesh.topology
        known = {}  # values a system computed at this x (the last trial step), if any
        for system in self._systems.values():
            known = {**system.cached(Vs), **known}
        k = kernels.get()  # the systems' values come from the kernels when they exist: so do these
        if "phi" in known:
            phi = known["phi"]
        else:
            phi = angle_values(Vs[self.vid]) if k is None else k.angles(Vs, self.vid, False)[0]
        w = phi[t.star_corners[t.interior_valence4, :4]]
        quads = np.nonzero(self.mesh.face_sizes == 4)[0]
        q = phi[t.offsets[quads][:, None] + np.arange(4)]
        if k is not None and self._quads_only:
            plan = float(k.quad_planarity_max(Vs, self.quads))
        else:
            plan = float(measures.planarity(self.mesh, Vs).max(initial=0.0))
        out = {"planarity": plan,
               "conical": float(np.abs(w[:, 0] - w[:, 1] + w[:, 2] - w[:, 3]).max(initial=0.0)),
               "circular": float(np.maximum(np.abs(q[:, 0] + q[:, 2] - np.pi),
                                            np.abs(q[:, 1] + q[:, 3] - np.pi)).max(initial=0.0))}
        if self.has_quads:
            if "D" in known:
                D = known["D"]
            else:
                D = det_values(Vs[self.quads]) if k is None else k.dets(Vs, self.quads, False)[0]
            out["det"] = float(np.abs(D).max())
        out["fairness"] = float(np.sum(self.fairness(x)[0] ** 2))
        return out

    def tolerance(self, name: str) -> float:
        """Tolerance of a tested defect (``det`` uses the planarity tolerance: ``Tolerances.for_defect``)."""
        return self.tol.for_defect(name)

    def converged(self, m: dict) -> bool:
        """True when every tested defect in ``m`` is within its tolerance."""
        return all(m[k] <= self.tolerance(k) for k in self.tests)

    def worst(self, m: dict) -> float:
        """max over tested defects of defect / tolerance (<= 1 means converged)."""
        return max(m[k] / self.tolerance(k) for k in self.tests)

    def describe(self, m: dict) -> str:
        """'planarity 3.1e-07 <= 1e-06, det ...' for messages."""
        return ", ".join(f"{k} {m[k]:.3g} {'<=' if m[k] <= self.tolerance(k) else '>'} "
                         f"{self.tolerance(k):.3g}" for k in self.tests)

    def max_distance(self, V: np.ndarray) -> float:
        """Largest distance of ``V (n, 3)`` to the reference, relative to its bbox diagonal."""
        return float(self._distances(V).max(initial=0.0) / self.ref.bbox_diagonal)

    def _distances(self, V: np.ndarray) -> np.ndarray:
        """(n,) float: distances of the model positions ``V (n, 3)`` to the reference, in ``h``."""
        Vs = self.scaled(V)
        return np.linalg.norm(Vs - self.foot_search.closest(Vs)[0], axis=1)

    def result(self, x: np.ndarray, *, status: str, nit: int, history: list, timings: dict,
               method: str, message: str, multipliers: np.ndarray | None = None) -> OptimizeResult:
        """Build the :class:`OptimizeResult` for the final scaled vector ``x``."""
        V = self.positions(x) if nit else self.mesh.V.copy()  # no step taken: bit-exact input
        if len(self.fixed):
            V[self.fixed] = self.mesh.V[self.fixed]  # exactly where they were
        out = self.mesh.with_vertices(V, name=f"{self.mesh.name}+{method}-{self.target}")
        m = self.measure(x)
        defects = measures.summary(out, self.tol)
        if "det" in m:
            defects["det"] = {"max": m["det"], "tolerance": self.tol.planarity,
                              "ok": bool(m["det"] <= self.tol.planarity)}
        success = status == "converged" and self.converged(m)
        if status == "converged" and not success:
            status = "stalled"
        dist = self._distances(V)  # in h
        axes = cones = None
        if self.target == "conical":
            axes, cones = node_axes(out)
        res = OptimizeResult(
            mesh=out, success=success, status=status, message=message, nit=nit, history=history,
            defects=defects, max_distance=float(dist.max(initial=0.0) / self.ref.bbox_diagonal),
            normals=measures.face_normals(out), axes=axes, cone_angles=cones,
            multipliers=multipliers, timings=timings, method=method, target=self.target)
        record_shape(res, self.mesh, dist * self.h, self.ref.bbox_diagonal * self.h)
        record_net(res, self.mesh, self.target)
        return check_folds(res, self.mesh.V, fold_advice(self.target, method), self.tol.fold)


PAPER_FOLD_ADVICE = ("the paper's methods do not keep faces convex; the default method does "
                     "(method 'default', --method default)")


def fold_advice(target: str, method: str) -> str:
    """The way forward a folded run's message ends with.  For ``target`` pq, conical and
    circular the default method keeps faces convex; a strip has only the paper's methods
    (``--method default`` runs penalty there), so the advice names the others than ``method``
    and the fairness weight."""
    if target != "strip":
        return PAPER_FOLD_ADVICE
    others = [m for m in ("penalty", "sqp", "hybrid") if m != method]
    names = ", ".join(f"'{m}'" for m in others)
    return (f"the paper's methods do not keep faces convex, and target 'strip' has no other method "
            f"(the default method does not take strips); try another of them (method {names}, "
            f"--method {others[0]}) or a larger fairness weight (fairness, --fairness)")


def node_axes(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Unit node axes ``(n, 3)`` and cone angles ``(n,)`` of a (near) conical mesh: the
    offset stage's fit to the unit face normals (:func:`optimize.mesh.axes.fit_axes`); at a
    conical vertex the axis of the circle the normals lie on."""
    fit = fit_axes(mesh, measures.face_normals(mesh))
    return fit.axes, np.arccos(np.clip(fit.cos_theta, -1.0, 1.0))
