"""The paper's penalty method: Gauss-Newton with Levenberg-Marquardt damping.

Minimizes (paper section 2.2)

    E(x) = |c_angle(x)|^2 + mu |c_det(x)|^2 + w1 |K x|^2 + w2 |r_close(x)|^2

where ``c_angle`` stacks the target's angle rows (angle sums; plus the conical
balance, or the circular pairs instead of the sums) and ``c_det`` the strip
determinants (``mu = 1`` for strips).  Each iteration linearizes every row
(closeness footpoints recomputed once per iteration) and solves the damped
normal equations

    (J^T J + lam D) s = -J^T R,      D = diag(J^T J) (floored),

(``lam`` starts at ``1e-2``), accepting the step when the gain ratio ``rho`` (actual / predicted decrease of
``E``) is positive (then ``lam`` shrinks by Nielsen's rule), otherwise ``lam``
grows and the system is solved again.  After every iteration ``w1`` and ``w2``
are halved, so the angle terms dominate more and more and the constraints
become exact.

Linear algebra: where a reverse Cuthill-McKee ordering makes ``J^T J`` a
narrow band (strips, small meshes; :func:`optimize.solvers.paper.assembly.gram_band`)
it is assembled directly into band storage on a pattern fixed for the run and
factored by LAPACK's banded Cholesky, or, with the compiled kernels
(:mod:`optimize.kernels`), by their ``L D L^T`` inside the band's
envelope; otherwise (or if that factorization finds the matrix not positive
definite) by :class:`optimize.linalg.spd.SPDSolver` (SuperLU, then the LSQR
fallback for near-singular systems: see :mod:`optimize.linalg.spd`).  The
predicted decrease needs ``s^T J^T J s``; after a banded solve it is
``-g.s - lam s^T D s``, without a product with the matrix.

Stops on tests: every tested defect within tolerance (``converged``), no step
lowering ``E`` or no progress of the worst defect/tolerance ratio for
``patience`` iterations (``stalled``), non-finite values (``diverged``, the
last good iterate is kept), or ``max_iter``.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.linalg.blas import dsbmv

from ...linalg.banded import cholesky_solve
from ...linalg.spd import SPDSolver
from ...mesh import Mesh
from ...options import DEFAULTS
from ...result import OptimizeResult
from ...tolerances import DEFAULT, Tolerances
from .assembly import gram_band
from .cache import problem_for
from .problem import Problem

log = logging.getLogger(__name__)

LAM_START, LAM_MAX, TRIES = 1e-2, 1e12, 30


@dataclass
class Run:
    """State handed between phases: final ``x``, how the run ended, history, timings."""

    x: np.ndarray
    status: str = "max_iter"
    message: str = ""
    nit: int = 0
    history: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    multipliers: np.ndarray | None = None
    weights: tuple[float, float] = (0.0, 0.0)  # (w1, w2) the next iteration would use


class Linearized:
    """The damped normal equations ``(J^T J + lam D) s = -J^T R`` of one penalty iterate.

    p : Problem.  x : (3 n,) scaled positions.  w1, w2 : current weights.
    foot : closeness footpoints ``(Y (n, 3), N (n, 3))`` or None (``w2 = 0``).
    band : the run's :class:`optimize.solvers.paper.assembly.GramBand`, or None for the
    sparse path, which solves with ``solver`` (:class:`optimize.linalg.spd.SPDSolver`).

    ``J`` and ``R`` stack the weighted constraint rows, ``sqrt(w1) K`` and
    ``sqrt(w2) C``; attributes ``E = |R|^2``, ``g = J^T R (k,)``, ``D (k,)``
    the floored diagonal of ``J^T J`` (in the band's order on the banded path).
    """

    def __init__(self, p: Problem, x: np.ndarray, w1: float, w2: float, foot, band, solver: SPDSolver):
        self.p, self.band, self.solver = p, band, solver
        P = p.system.pattern
        c, self.a = p.system.evaluate_data(p.vertices(x), jac=True, weighted=True)
        f, gh = p.least_squares(x, w1, w2, foot)
        self.E = float(c @ c) + f
        self.g = np.bincount(P.indices, weights=self.a * c[P.rows], minlength=P.shape[1]) + gh
        self._w, self._normals = (w1, w2), None if foot is None else foot[1]
        self._h = self._N = None
        if band is not None:
            self.ab = band.assemble_objective(self.a, w1, w2, self._normals)  # (bw + 1, k), ordered
            d = self.ab[0]
        else:
            d = self.normal_matrix().diagonal()
        self.D = np.maximum(d, 1e-9 * max(float(d.max(initial=0.0)), 1.0))  # ordered like d

    @property
    def h(self) -> np.ndarray:
        """Values of ``w1 K^T K + w2 C^T C`` on ``Problem.hpat`` (for the sparse path)."""
        if self._h is None:
            self._h = self.p.hessian_data(*self._w, self._normals)
        return self._h

    def normal_matrix(self) -> sp.csr_matrix:
        """(k, k) sparse ``J^T J``."""
        if self._N is None:
            A = self.p.system.pattern.csr(self.a)
            self._N = (A.T @ A + self.p.hpat.csr(self.h)).tocsr()
        return self._N

    def solve(self, lam: float) -> tuple[np.ndarray, str]:
        """The step ``s (k,)`` for damping ``lam`` and how it was solved ("banded", "lu", "lsqr")."""
        if self.band is not None:
            ab = self.ab.copy(order="F")  # LAPACK's layout: no copy inside dpbtrf
            ab[0] += lam * self.D
            s = cholesky_solve(ab, -self.g, self.band.order)
            if s is not None:
                return s, "banded"
            D = np.empty_like(self.D)
            D[self.band.order.perm] = self.D
        else:
            D = self.D
        return self.solver.solve(self.normal_matrix() + lam * sp.diags(D), -self.g)

    def curvature(self, s: np.ndarray, lam: float | None = None) -> float:
        """``s^T J^T J s``.  ``lam``: ``s`` solved ``(J^T J + lam D) s = -g`` exactly (the banded
        factorization, backward stable for this positive definite matrix); then it is
        ``-g.s - lam s^T D s`` and no product with the matrix is needed."""
        if lam is not None and self.band is not None:
            so = s[self.band.order.perm]
            return float(-(self.g @ s) - lam * float(so @ (self.D * so)))
        if self.band is not None:
            so = s[self.band.order.perm]
            return float(so @ dsbmv(self.band.order.bw, 1.0, self.ab, so, lower=1))
        return float(s @ (self.normal_matrix() @ s))


def energy(p: Problem, x: np.ndarray, w1: float, w2: float, foot) -> float:
    """The penalty energy ``E`` at ``x`` (footpoints ``foot`` fixed)."""
    c = p.system.evaluate_data(p.vertices(x), jac=False, weighted=True)
    return float(c @ c) + p.least_squares(x, w1, w2, foot, grad=False)


def run_penalty(p: Problem, x: np.ndarray, *, max_iter: int, callback=None, patience: int = 20,
                stop_at: float = 1.0, w1: float | None = None, w2: float | None = None) -> Run:
    """Iterate from the scaled vector ``x (3 n,)``.

    stop_at : stop ("converged") when the worst tested defect/tolerance ratio
        is at most this (1 = the tolerances; the hybrid method stops earlier).
    w1, w2 : starting weights (default the problem's ``fairness``, ``closeness``).
    """
    t0 = time.perf_counter()
    tm = {"assemble": 0.0, "solve": 0.0, "measure": 0.0}  # assemble includes closest points
    w1 = p.w_fair if w1 is None else w1
    w2 = p.w_close if w2 is None else w2
    run = Run(x=x.copy())
    m = p.measure(x)
    best = score = p.worst(m)
    since, lam, nu = 0, LAM_START, 2.0
    solver = SPDSolver()
    band = p.band("gram", lambda q: gram_band(q, q.system))
    if score <= stop_at:
        run.status, run.message = "converged", f"the input already satisfies the tolerances ({p.describe(m)})"
    while run.status == "max_iter" and run.nit < max_iter:
        ti = time.perf_counter()
        foot = p.footpoints(x) if w2 > 0 else None
        lin = Linearized(p, x, w1, w2, foot, band, solver)
        E = lin.E
        tm["assemble"] += time.perf_counter() - ti
        accepted, tries, how = False, 0, "lu"
        while not accepted and tries < TRIES and lam <= LAM_MAX:
            tries += 1
            ts = time.perf_counter()
            s, how = lin.solve(lam)
            tm["solve"] += time.perf_counter() - ts
            xn = p.step(x, s)
            ta = time.perf_counter()
            En = energy(p, xn, w1, w2, foot)
            tm["assemble"] += time.perf_counter() - ta
            pred = float(-2 * (lin.g @ s) - lin.curvature(s, lam if how == "banded" else None))
            rho = (E - En) / pred if pred > 0 else -1.0
            if np.isfinite(En) and rho > 1e-8:
                accepted = True
                lam *= max(1 / 3, 1 - (2 * rho - 1) ** 3)
                nu = 2.0
            else:
                lam *= nu
                nu *= 2
        if not accepted:
            run.status = "stalled"
            run.message = (f"no step lowers the penalty energy (damping {lam:.3g}); "
                           f"{p.describe(m)}")
            break
        if not np.all(np.isfinite(xn)):
            run.status, run.message = "diverged", f"iteration {run.nit + 1}: non-finite positions"
            break
        run.nit += 1
        step = float(np.abs(xn - x).max())
        x = xn
        tq = time.perf_counter()
        m = p.measure(x)
        tm["measure"] += time.perf_counter() - tq
        score = p.worst(m)
        entry = {"iteration": run.nit, "phase": "penalty", **m, "energy": En, "step": step,
                 "damping": lam, "tries": tries, "solve": how, "w_fair": w1, "w_close": w2,
                 "seconds": time.perf_counter() - ti}
        run.history.append(entry)
        log.debug("penalty %d: %s", run.nit, entry)
        if callback is not None:
            callback(entry)
        if score <= stop_at:
            run.status = "converged"
            run.message = f"penalty: tolerances reached in {run.nit} iterations ({p.describe(m)})"
        elif score < 0.99 * best:
            best, since = score, 0
        else:
            since += 1
            if since >= patience:
                run.status = "stalled"
                run.message = f"penalty: no progress in {patience} iterations ({p.describe(m)})"
        w1 *= 0.5
        w2 *= 0.5
    if run.status == "max_iter":
        run.message = f"penalty: stopped at max_iter={max_iter} ({p.describe(m)})"
    run.x = x
    run.weights = (w1, w2)
    tm["total"] = time.perf_counter() - t0
    run.timings = tm
    return run


def penalty(mesh: Mesh, target: str = "pq", *, reference: Mesh | None = None, fixed=None,
            fairness: float = DEFAULTS.fairness, closeness: float = DEFAULTS.closeness, tol: Tolerances = DEFAULT,
            max_iter: int = DEFAULTS.max_iter, callback=None, mu: float | None = None) -> OptimizeResult:
    """Run the penalty method on ``mesh`` (unchanged) and return an :class:`OptimizeResult`.

    Parameters are those of :func:`optimize.solvers.paper.run_paper_method`; ``mu`` is
    the weight of the strip determinants (default 1 for ``strip``, else 0).
    """
    t0 = time.perf_counter()
    with problem_for(mesh, target, reference=reference, fixed=fixed, fairness=fairness,
                     closeness=closeness, tol=tol, mu=mu, method="penalty") as p:
        run = run_penalty(p, p.x0(), max_iter=max_iter, callback=callback)
        run.timings["total"] = time.perf_counter() - t0
        return p.result(run.x, status=run.status, nit=run.nit, history=run.history, timings=run.timings,
                        method="penalty", message=run.message)
