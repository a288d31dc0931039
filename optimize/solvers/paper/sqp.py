"""The paper's SQP method: Newton-KKT steps with a soft line search.

Minimizes ``f(x) = w1 |K x|^2 + w2 |r_close(x)|^2`` subject to the target's
constraints ``c(x) = 0`` (paper eq. 3; the rows of the penalty method, the
determinant rows included as constraints).  Each iteration solves the KKT
system of the quadratic model

    [ H + delta I    A^T    ] [ s  ]     [ g + A^T y ]
    [ A           -eps I    ] [ dy ] = - [ c         ]

with ``g = grad f``, ``H = 2 (w1 K^T K + w2 C^T C)`` (the closeness Hessian by
its Gauss-Newton approximation), ``A = dc/dx`` and the multipliers ``y``
(``grad f + A^T y = 0`` at a KKT point), updated to ``y + alpha dy``.  By
default the constraint curvature ``sum y_i Hess c_i`` is left out (a
Gauss-Newton SQP step); ``hessian="exact"`` adds it
(:mod:`optimize.solvers.paper.hessian`), which makes the stationarity converge fast
once the multipliers are settled (see ``--sweep`` below for how often each
converges).  SQP's rows are
the description's constraints (:func:`optimize.terms.problem.describe`: determinants
instead of angle sums for quads).

Near-singular systems (the paper falls back to an SVD):

- ``eps = 1e-8`` (a stabilized-SQP block, S. Wright 1998) keeps the matrix
  non-singular for redundant or degenerate rows (rows whose gradients are
  dependent or vanish at the solution; the description's constraints
  (:func:`optimize.terms.problem.describe`) leave out the known ones), whose multipliers are not unique or do not
  exist; the linearized constraints then hold up to ``eps |dy|``.
- ``delta`` is a proximal (Levenberg-Marquardt) term: the tangent-plane
  closeness and the fairness leave ``H`` singular (vertices may slide along
  the surface), so without it the steps would be unbounded along the
  constraint set.  It starts at ``1e-3``, is divided by 3 after a full step
  and multiplied by 2 (``alpha >= 1/4``) or 8 after a shortened one; it is
  multiplied by 8 also after any step that leaves the constraints worse
  than they were, ``|c(x + s)|_inf > max(|c(x)|_inf, tau)`` (``tau`` the
  smallest tested tolerance): the step was longer than the region where the
  linearized constraints hold, and ``delta`` shortens only the objective's
  part of the step, not the restoring one.  Without that test the merit
  function alone steers the proximal weight, and it prices
  infeasibility by ``rho ~ |y|_inf``, which is tiny when the objective is
  (small weights ``w1, w2``): on the trefoil bands full steps were accepted
  while ``delta`` fell to ``1e-9``, the steps grew to a third of an edge,
  the neglected constraint curvature made them lose feasibility faster than
  the Newton steps restored it (``|c|_1`` from 2e-4 to 2e-2 while the merit
  still decreased), and SQP stalled at planarity 1e-3.
- Where a reverse Cuthill-McKee ordering makes the KKT matrix a narrow band
  (strips, small meshes; :func:`optimize.solvers.paper.assembly.kkt_band`) LAPACK's
  banded LU with partial pivoting factors it, refilled on a layout fixed for
  the run (with the compiled kernels of :mod:`optimize.kernels` an
  ``L D L^T`` without pivoting is tried first: the matrix is quasi-definite);
  otherwise, or when a banded solution fails the checks (not finite,
  relative residual above 1e-8, near-singular), SuperLU does; a failed or
  inaccurate SuperLU solve falls back to LSQR (:func:`optimize.linalg.spd.solve`).

Soft line search: the full step, then the full step with a second-order
correction (a minimum-norm step back onto the linearized constraints, same
factorization), then ``alpha = 1/2, 1/4, ... >= 1/64``: the first that lowers
the l1 merit ``f + rho |c|_1`` by Armijo's rule (``rho`` is at least
``1.1 |y|_inf`` and the value of Nocedal & Wright (18.36) that makes the step
a descent direction; with the Gauss-Newton Hessian it never decreases, with
the exact one it is recomputed every iteration so that full Newton steps stay
acceptable near the solution); if none does, the ``alpha`` with the lowest
merit is taken anyway (the run never stops on a failed line search).
``benchmarks/bench_paper.py --sweep`` counts how often SQP and hybrid
converge from the test inputs and a family of trefoil bands, per Hessian.

Stops when every tested defect is within tolerance and the KKT stationarity
``|g + A^T y|_inf <= kkt_tol * max(1, |g|_inf)`` holds, or ``kkt_patience``
iterations after the defects first were within tolerance (stationarity
converges only linearly without constraint curvature): then the last iterate
within tolerance is returned (pursuing the objective, e.g. vertices sliding
along the reference, can cost feasibility faster than the Newton steps
restore it).  Otherwise it stops on no progress for ``patience`` iterations,
non-finite values, or ``max_iter``.
"""
from __future__ import annotations

import logging
import time

import numpy as np
import scipy.sparse as sp

from ...linalg.spd import COND_LIMIT, RESIDUAL_TOL, Factor
from ...mesh import Mesh
from ...options import DEFAULTS
from ...result import OptimizeResult
from ...tolerances import DEFAULT, Tolerances
from .assembly import kkt_band
from .cache import problem_for
from .hessian import constraint_curvature
from .penalty import Run
from .problem import Problem

log = logging.getLogger(__name__)

EPS = 1e-8
DELTA_START, DELTA_MIN, DELTA_MAX = 1e-3, 1e-10, 1e8
KKT_TOL, KKT_PATIENCE = 1e-6, 10  # the stationarity test's defaults (module docstring)
ALPHA_MIN = 1.0 / 64


def objective(p: Problem, x: np.ndarray, w1: float, w2: float, derivatives: bool = True, foot=None):
    """``f`` at ``x`` (and ``g (k,)``, ``H (k, k)`` on the free coordinates).

    foot : closeness footpoints ``(Y, N)`` (recomputed at ``x`` when None).
    ``H`` is stored on the fixed pattern :attr:`optimize.solvers.paper.problem.Problem.hpat`.
    """
    if not derivatives:
        return p.least_squares(x, w1, w2, foot, grad=False)
    if w2 > 0 and foot is None:
        foot = p.footpoints(x)
    f, gh = p.least_squares(x, w1, w2, foot)
    H = p.hpat.csr(2 * p.hessian_data(w1, w2, None if foot is None else foot[1]))
    return f, 2 * gh, H


def kkt_matrix(H: sp.spmatrix, A: sp.spmatrix, delta: float, eps: float = EPS) -> sp.csc_matrix:
    """((k + r), (k + r)) sparse: ``[[H + delta I, A^T], [A, -eps I]]``."""
    k, r = H.shape[0], A.shape[0]
    return sp.bmat([[H + delta * sp.identity(k), A.T], [A, -eps * sp.identity(r)]], format="csc")


class KKTFactor:
    """Solves with the KKT matrix :func:`kkt_matrix` ``(H, A, delta, eps)``, factored once.

    band : an :class:`optimize.solvers.paper.assembly.KKTBand` (then ``h_data``, the values
    of ``H`` on ``Problem.hpat``, ``a_data``, those of ``A`` on its pattern, and
    ``extra``, a sparse addition to ``H``, fill it) or None.  The banded LU's
    solutions pass the checks of :class:`optimize.linalg.spd.Factor` (finite,
    relative residual <= 1e-8, not near-singular); if one does not, the sparse
    path (SuperLU, then LSQR) is used, as without a band.
    """

    def __init__(self, H, A, delta: float, eps: float = EPS, band=None, h_data=None, a_data=None,
                 extra=None):
        self.H, self.A, self.delta, self.eps = H, A, delta, eps
        self.lu = None if band is None else band.factor(h_data, a_data, delta, eps, extra)
        self._sparse = None

    def _residual(self, x: np.ndarray, b: np.ndarray) -> float:
        k = self.H.shape[0]
        s, dy = x[:k], x[k:]
        top = self.H @ s + self.delta * s + self.A.T @ dy - b[:k]
        bottom = self.A @ s - self.eps * dy - b[k:]
        return float(np.sqrt(top @ top + bottom @ bottom))

    def solve(self, b: np.ndarray) -> tuple[np.ndarray, str]:
        """``x (k + r,)`` and how it was solved: "banded", "lu" or "lsqr"."""
        if self.lu is not None:
            bn = float(np.linalg.norm(b))
            if bn == 0.0:
                return np.zeros_like(b), "banded"
            for solve in self.lu.solvers():
                x = solve(b)
                if (np.all(np.isfinite(x)) and self._residual(x, b) <= RESIDUAL_TOL * bn
                        and np.linalg.norm(x) * self.lu.norm1 <= COND_LIMIT * bn):
                    return x, "banded"
        if self._sparse is None:
            self._sparse = Factor(kkt_matrix(self.H, self.A, self.delta, self.eps), symmetric=False)
        return self._sparse.solve(b)


def kkt_step(H: sp.spmatrix, A: sp.spmatrix, g: np.ndarray, c: np.ndarray, y: np.ndarray,
             delta: float, eps: float = EPS, factor=None):
    """Step ``s (k,)`` and multiplier change ``dy (r,)`` from the KKT system; and how it was solved.

    factor : a :class:`KKTFactor` (or :class:`optimize.linalg.spd.Factor`) of
    :func:`kkt_matrix` to reuse.
    """
    k = H.shape[0]
    factor = KKTFactor(H, A, delta, eps) if factor is None else factor
    sol, how = factor.solve(-np.concatenate([g + A.T @ y, c]))
    return sol[:k], sol[k:], how


def kkt_residual(p: Problem, x: np.ndarray, y: np.ndarray, w1: float | None = None,
                 w2: float | None = None) -> dict:
    """KKT conditions at ``x`` (scaled) for multipliers ``y (r,)``.

    Returns ``stationarity = |g + A^T y|_inf``, ``gradient = |g|_inf`` and
    ``feasibility = |c|_inf`` (footpoints recomputed at ``x``).
    """
    w1 = p.w_fair if w1 is None else w1
    w2 = p.w_close if w2 is None else w2
    _, g, _ = objective(p, x, w1, w2)
    c, A, _ = p.constraints(x, sqp=True)
    return {"stationarity": float(np.abs(g + A.T @ y).max(initial=0.0)),
            "gradient": float(np.abs(g).max(initial=0.0)), "feasibility": float(np.abs(c).max(initial=0.0))}


def _rho_needed(s: np.ndarray, g: np.ndarray, H: sp.spmatrix, c: np.ndarray, delta: float) -> float:
    """The l1 penalty that makes ``s`` a descent direction with weight on feasibility.

    Nocedal & Wright (18.36): ``rho >= (g.s + s.Hs / 2) / ((1 - sigma) |c|_1)``, ``sigma = 0.1``.
    Without it a small objective (small weights) leaves feasibility almost unpriced.
    """
    c1 = float(np.abs(c).sum())
    if c1 <= 0.0:
        return 0.0
    return max(float(g @ s) + 0.5 * max(float(s @ (H @ s)) + delta * float(s @ s), 0.0), 0.0) / (0.9 * c1)


def _line_search(p: Problem, x, s, f, c, g, rho, w1, w2, foot, correction):
    """Soft backtracking on the l1 merit ``f + rho |c|_1``.

    The full step is tried first as it is, then with the second-order
    correction ``correction(c(x + s))`` (a minimum-norm step back onto the
    linearized constraints, the same factorization), then ``alpha = 1/2, 1/4, ...``.
    Returns the accepted step vector, ``alpha`` (None when every merit is non-finite)
    and the constraint values at ``x`` plus that step.
    """
    def merit(xa):
        ca = p.constraints(xa, jac=False, sqp=True)
        return objective(p, xa, w1, w2, derivatives=False, foot=foot) + rho * float(np.abs(ca).sum()), ca

    phi0 = f + rho * float(np.abs(c).sum())
    slope = min(float(g @ s) - rho * float(np.abs(c).sum()), 0.0)
    best = (np.inf, None, None, None)
    phi1, c1 = merit(p.step(x, s))
    if np.isfinite(phi1) and phi1 <= phi0 + 1e-4 * slope:
        return s, 1.0, c1
    best = min(best, (phi1, 1.0, s, c1), key=lambda t: t[0]) if np.isfinite(phi1) else best
    if np.all(np.isfinite(c1)):
        s2 = s + correction(c1)
        phi2, c2 = merit(p.step(x, s2))
        if np.isfinite(phi2) and phi2 <= phi0 + 1e-4 * slope:
            return s2, 1.0, c2
    alpha = 0.5
    while alpha >= ALPHA_MIN:
        phia, ca = merit(p.step(x, s, alpha))
        if np.isfinite(phia) and phia < best[0]:
            best = (phia, alpha, alpha * s, ca)
        if np.isfinite(phia) and phia <= phi0 + 1e-4 * alpha * slope:
            return alpha * s, alpha, ca
        alpha *= 0.5
    return best[2], best[1], best[3]


DELTA_RULE = (3.0, 2.0, 8.0)


def _adapt(delta: float, alpha: float, trusted: bool = True) -> float:
    """The proximal weight after a step of length ``alpha``; ``trusted``: the step did not
    leave the constraints worse than they were (see the module docstring)."""
    down, mid, up = DELTA_RULE
    if not trusted:
        return min(delta * up, DELTA_MAX)
    if alpha == 1.0:
        return max(delta / down, DELTA_MIN)
    return min(delta * (mid if alpha >= 0.25 else up), DELTA_MAX)


def run_sqp(p: Problem, x: np.ndarray, *, max_iter: int, callback=None, kkt_tol: float = KKT_TOL,
            kkt_patience: int = KKT_PATIENCE, patience: int = 20, first_iteration: int = 0,
            y: np.ndarray | None = None, hessian: str = "gauss-newton",
            weights: tuple[float, float] | None = None) -> Run:
    """Iterate from the scaled vector ``x (3 n,)`` (multipliers ``y`` or zeros).

    weights : fixed ``(w1, w2)`` of the objective (default the problem's).
    """
    t0 = time.perf_counter()
    tm = {"assemble": 0.0, "solve": 0.0, "measure": 0.0, "line_search": 0.0}
    w1, w2 = (p.w_fair, p.w_close) if weights is None else weights
    run = Run(x=x.copy(), weights=(w1, w2))
    best, since, since_ok, delta, rho = np.inf, 0, 0, DELTA_START, 0.0
    last_ok = None  # (x, measures, stationarity, multipliers, iteration, history length) within tolerance
    m = p.measure(x)
    it = 0
    band = p.band(f"kkt_{hessian}", lambda q: kkt_band(q, q.sqp_system, exact=hessian == "exact"))
    c_floor = min(p.tolerance(name) for name in p.tests)  # constraint values that count as met
    while it < max_iter:
        ti = time.perf_counter()
        foot = p.footpoints(x) if w2 > 0 else None
        f, g, H = objective(p, x, w1, w2, foot=foot)
        c, a = p.sqp_system.evaluate_data(p.vertices(x))
        A, blocks = p.sqp_system.pattern.csr(a), p.sqp_system.blocks
        y = np.zeros(len(c)) if y is None else y
        h_data, curvature = H.data, None
        if hessian == "exact" and np.any(y):
            curvature = p.cols2(constraint_curvature(p.mesh, p.sqp_terms, p.vertices(x), y, blocks))
            H = H + curvature
        tm["assemble"] += time.perf_counter() - ti
        ts = time.perf_counter()
        factor = KKTFactor(H, A, delta, band=band, h_data=h_data, a_data=a, extra=curvature)
        s, dy, how = kkt_step(H, A, g, c, y, delta, factor=factor)
        tm["solve"] += time.perf_counter() - ts
        if not (np.all(np.isfinite(s)) and np.all(np.isfinite(dy))):
            run.status, run.message = "diverged", f"iteration {first_iteration + it + 1}: non-finite KKT solution"
            break
        y_new = y + dy
        stat = float(np.abs(g + A.T @ y_new).max(initial=0.0))
        run.multipliers = y_new
        ok = p.converged(m)
        if ok:
            last_ok = (x, m, stat, y_new, it, len(run.history))
        if last_ok is not None:
            since_ok += 1
        if ok and stat <= kkt_tol * max(1.0, float(np.abs(g).max(initial=0.0))):
            run.status = "converged"
            run.message = (f"sqp: tolerances and KKT stationarity reached in {it} iterations "
                           f"({p.describe(m)}; stationarity {stat:.3g})")
            break
        if since_ok > kkt_patience:  # the last iterate within tolerance
            x, m, stat, run.multipliers, it, nh = last_ok
            del run.history[nh:]
            run.status = "converged"
            run.message = (f"sqp: tolerances reached in {it} iterations ({p.describe(m)}; KKT "
                           f"stationarity {stat:.3g}: the next {kkt_patience} iterations did not reach "
                           f"{kkt_tol:g} within the tolerances)")
            break
        tl = time.perf_counter()
        rho = max(rho if hessian != "exact" else 0.0, 1.1 * float(np.abs(y_new).max(initial=0.0)),
                  _rho_needed(s, g, H, c, delta))
        k = len(s)

        def correction(c1):
            return factor.solve(-np.concatenate([np.zeros(k), c1]))[0][:k]

        step_vec, alpha, c_new = _line_search(p, x, s, f, c, g, rho, w1, w2, foot, correction)
        tm["line_search"] += time.perf_counter() - tl
        if alpha is None:
            run.status, run.message = "diverged", f"iteration {first_iteration + it + 1}: non-finite merit"
            break
        xn = p.step(x, step_vec)
        y = y + alpha * dy
        # the step may not leave the constraints worse than they were (or than the tolerance)
        trusted = float(np.abs(c_new).max(initial=0.0)) <= max(float(np.abs(c).max(initial=0.0)), c_floor)
        delta = _adapt(delta, alpha, trusted)
        it += 1
        step = float(np.abs(xn - x).max())
        x = xn
        tq = time.perf_counter()
        m = p.measure(x)
        tm["measure"] += time.perf_counter() - tq
        entry = {"iteration": first_iteration + it, "phase": "sqp", **m, "objective": f,
                 "feasibility": float(np.abs(c).max(initial=0.0)), "kkt": stat, "alpha": alpha,
                 "step": step, "trusted": trusted, "delta": delta, "rho": rho, "solve": how,
                 "seconds": time.perf_counter() - ti,
                 "multiplier_blocks": {n: [b.start, b.stop] for n, b in blocks.items()}}
        run.history.append(entry)
        log.debug("sqp %d: %s", it, entry)
        if callback is not None:
            callback(entry)
        score = p.worst(m)
        if score < 0.99 * best or ok:
            best, since = min(best, score), 0
        else:
            since += 1
            if since >= patience:
                run.status = "stalled"
                run.message = f"sqp: no progress in {patience} iterations ({p.describe(m)})"
                break
    else:
        run.message = f"sqp: stopped at max_iter={max_iter} ({p.describe(m)})"
    run.nit = it
    run.x = x
    tm["total"] = time.perf_counter() - t0
    run.timings = tm
    return run


HESSIANS = ("gauss-newton", "exact")


def check_hessian(hessian: str) -> str:
    if hessian not in HESSIANS:
        from ...errors import ConfigError
        raise ConfigError(f"hessian: {hessian!r} is not known, expected one of {HESSIANS}")
    return hessian


def sqp(mesh: Mesh, target: str = "pq", *, reference: Mesh | None = None, fixed=None,
        fairness: float = DEFAULTS.fairness, closeness: float = DEFAULTS.closeness, tol: Tolerances = DEFAULT,
        max_iter: int = DEFAULTS.max_iter, callback=None, mu: float | None = None,
        kkt_tol: float = KKT_TOL, kkt_patience: int = KKT_PATIENCE, hessian: str = "gauss-newton") -> OptimizeResult:
    """Run SQP on ``mesh`` (unchanged); the result's ``multipliers`` are those of the last KKT solve.

    Multipliers are ordered like the constraint rows: the blocks of
    the description's constraints (``history[-1]["multiplier_blocks"]``).
    mu : > 0 adds the determinant rows (default: 1 on quad meshes, see
        :func:`optimize.terms.problem.default_mu`).
    kkt_tol, kkt_patience : the stationarity test (module docstring).
    hessian : "gauss-newton" (default) or "exact" (adds the constraint
        curvature ``sum y_i Hess c_i``, :mod:`optimize.solvers.paper.hessian`).
    """
    t0 = time.perf_counter()
    with problem_for(mesh, target, reference=reference, fixed=fixed, fairness=fairness,
                     closeness=closeness, tol=tol, mu=mu, method="sqp") as p:
        run = run_sqp(p, p.x0(), max_iter=max_iter, callback=callback, kkt_tol=kkt_tol,
                      kkt_patience=kkt_patience, hessian=check_hessian(hessian))
        run.timings["total"] = time.perf_counter() - t0
        return p.result(run.x, status=run.status, nit=run.nit, history=run.history, timings=run.timings,
                        method="sqp", message=run.message, multipliers=run.multipliers)
