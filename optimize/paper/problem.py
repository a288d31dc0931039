"""The data of one run of the paper's methods, shared by penalty, SQP and hybrid.

Named variable layout: the unknown vector is ``x = ((V - c) / h).ravel()``, the
vertex positions centred at their mean ``c`` and divided by the mean edge
length ``h``, so that every residual and step is scale-free (angles and
determinants do not change, fairness is ``K x`` and closeness ``((v - y) . n) / h``).
Fixed vertices are removed: Jacobians are restricted to the ``free``
coordinates and steps are scattered back with :meth:`Problem.step`.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .. import measures
from ..closeness import Reference
from ..constraints.fixed import resolve
from ..fairness import fairness_matrix
from ..mesh import Mesh
from ..result import OptimizeResult
from ..tolerances import DEFAULT, Tolerances
from .angles import angle_values
from .det import det_values
from .system import ConstraintSystem, Pattern
from .targets import sqp_terms, target_terms, tested_defects


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
    mu : weight of the determinant terms (default 1 for strips, else 0).
    """

    def __init__(self, mesh: Mesh, target: str = "pq", *, reference: Mesh | None = None, fixed=None,
                 fairness: float = 1e-3, closeness: float = 1e-2, tol: Tolerances = DEFAULT,
                 mu: float | None = None):
        self.mesh, self.target, self.tol = mesh, target, tol
        self.terms = target_terms(mesh, target, mu)
        self.tests = tested_defects(target, mu)
        self.w_fair, self.w_close = float(fairness), float(closeness)
        if self.w_fair < 0 or self.w_close < 0:
            from ..errors import ConfigError
            raise ConfigError(f"fairness={fairness}, closeness={closeness}: weights must be >= 0")
        self.center = mesh.V.mean(axis=0)
        self.h = float(measures.edge_lengths(mesh).mean())
        n = mesh.n_vertices
        self.fixed = resolve(mesh, fixed)
        mask = np.ones(3 * n, dtype=bool)
        mask[(3 * self.fixed[:, None] + np.arange(3)).ravel()] = False
        self.free = np.nonzero(mask)[0]
        self._all_free = len(self.free) == 3 * n
        self.K_full = fairness_matrix(mesh)  # (3t, 3n)
        self.K = self._cols(self.K_full)  # (3t, k) on the free coordinates
        free = None if self._all_free else self.free
        self.system = ConstraintSystem(mesh, self.terms, free)
        self.sqp_terms = sqp_terms(mesh, self.terms)
        self.sqp_system = ConstraintSystem(mesh, self.sqp_terms, free)
        self._close = Pattern(np.repeat(np.arange(n), 3), np.arange(3 * n), (n, 3 * n),
                              None if self._all_free else self.free)
        self.reference = mesh if reference is None else reference
        self._ref = None
        self.has_quads = bool(np.any(mesh.face_sizes == 4))

    # -- variables ----------------------------------------------------------
    @property
    def ref(self) -> Reference:
        """The closest-point structure of the reference (built on first use)."""
        if self._ref is None:
            self._ref = Reference(self.reference)
        return self._ref

    def x0(self) -> np.ndarray:
        """(3 n,) float: the scaled input positions."""
        return ((self.mesh.V - self.center) / self.h).ravel()

    def positions(self, x: np.ndarray) -> np.ndarray:
        """(n, 3) float: model positions of the scaled vector ``x (3 n,)``."""
        return self.center + self.h * x.reshape(-1, 3)

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
        (:func:`optimize.paper.targets.sqp_terms`).
        """
        system = self.sqp_system if sqp else self.system
        out = system.evaluate(x.reshape(-1, 3), jac=jac, weighted=weighted)
        return (*out, system.blocks) if jac else out

    def fairness(self, x: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
        """Unweighted fairness rows ``(K x (3t,), K (3t, k))`` in mean-edge units."""
        return self.K_full @ x, self.K

    def footpoints(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Closest points ``Y (n, 3)`` (model units) and unit normals ``N (n, 3)`` on the reference."""
        return self.ref.closest(self.positions(x))

    def closeness(self, x: np.ndarray, foot=None, jac: bool = True):
        """Unweighted tangent-plane closeness rows ``(r (n,), J (n, k))`` at footpoints ``foot``.

        ``foot = (Y, N)`` from :meth:`footpoints` (recomputed at ``x`` when None).
        """
        Y, N = self.footpoints(x) if foot is None else foot
        r = np.einsum("ij,ij->i", self.positions(x) - Y, N) / self.h
        return (r, self._close.matrix(N)) if jac else r

    # -- measures and result ------------------------------------------------
    def measure(self, x: np.ndarray) -> dict:
        """Max defects at ``x``: planarity, conical, circular, det (quads), fairness energy."""
        Vs = x.reshape(-1, 3)  # every measure is scale-free: the scaled positions will do
        t = self.mesh.topology
        phi = angle_values(Vs[self.system.vid])  # the definitions of optimize.measures, angles once
        w = phi[t.star_corners[t.interior_valence4, :4]]
        quads = np.nonzero(self.mesh.face_sizes == 4)[0]
        q = phi[t.offsets[quads][:, None] + np.arange(4)]
        out = {"planarity": float(measures.planarity(self.mesh, Vs).max(initial=0.0)),
               "conical": float(np.abs(w[:, 0] - w[:, 1] + w[:, 2] - w[:, 3]).max(initial=0.0)),
               "circular": float(np.maximum(np.abs(q[:, 0] + q[:, 2] - np.pi),
                                            np.abs(q[:, 1] + q[:, 3] - np.pi)).max(initial=0.0))}
        if self.has_quads:
            out["det"] = float(np.abs(det_values(Vs[self.system.quads])).max())
        out["fairness"] = float(np.sum(self.fairness(x)[0] ** 2))
        return out

    def tolerance(self, name: str) -> float:
        """Tolerance of a tested defect (``det`` uses the planarity tolerance)."""
        return getattr(self.tol, "planarity" if name == "det" else name)

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

    def result(self, x: np.ndarray, *, status: str, nit: int, history: list, timings: dict,
               method: str, message: str, multipliers: np.ndarray | None = None) -> OptimizeResult:
        """Build the :class:`OptimizeResult` for the final scaled vector ``x``."""
        V = self.positions(x)
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
        axes = cones = None
        if self.target == "conical":
            axes, cones = node_axes(out)
        return OptimizeResult(
            mesh=out, success=success, status=status, message=message, nit=nit, history=history,
            defects=defects, max_distance=float(self.ref.distance(V).max() / self.ref.bbox_diagonal),
            normals=measures.face_normals(out), axes=axes, cone_angles=cones,
            multipliers=multipliers, timings=timings, method=method, target=self.target)


def node_axes(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Unit node axes ``(n, 3)`` and cone angles ``(n,)`` of a (near) conical mesh.

    At an interior valence-4 vertex the four unit face normals ``n_0..n_3`` lie
    on a circle of the unit sphere whose plane has normal ``a`` with
    ``(n_0 - n_2) . a = (n_1 - n_3) . a = 0``; ``a`` is oriented to the normals'
    side and ``theta = arccos(mean n_i . a)``.  Elsewhere (or where that cross
    product vanishes) the axis is the normalized mean of the face normals.
    """
    t = mesh.topology
    N = measures.face_normals(mesh)
    S = t.star_faces
    Ns = np.where((S >= 0)[:, :, None], N[np.maximum(S, 0)], 0.0)  # (n, s, 3)
    mean = Ns.sum(axis=1)
    mean /= np.maximum(np.linalg.norm(mean, axis=1, keepdims=True), 1e-300)
    axes = mean.copy()
    p = t.interior_valence4
    if len(p):
        n4 = N[S[p, :4]]
        a = np.cross(n4[:, 0] - n4[:, 2], n4[:, 1] - n4[:, 3])
        ln = np.linalg.norm(a, axis=1)
        ok = ln > 1e-12
        a = np.where(ok[:, None], a / np.where(ok, ln, 1.0)[:, None], mean[p])
        a *= np.where(np.einsum("ij,ij->i", a, mean[p]) < 0, -1.0, 1.0)[:, None]
        axes[p] = a
    cos = np.einsum("nsk,nk->ns", Ns, axes).sum(axis=1) / np.maximum(t.star_size, 1)
    return axes, np.arccos(np.clip(cos, -1.0, 1.0))
