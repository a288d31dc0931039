"""The paper's penalty method: Gauss-Newton with Levenberg-Marquardt damping.

Minimizes (paper section 2.2)

    E(x) = |c_angle(x)|^2 + mu |c_det(x)|^2 + w1 |K x|^2 + w2 |r_close(x)|^2

where ``c_angle`` stacks the target's angle rows (angle sums; plus the conical
balance, or the circular pairs instead of the sums) and ``c_det`` the strip
determinants (``mu = 1`` for strips).  Each iteration linearizes every row
(closeness footpoints recomputed once per iteration) and solves the damped
normal equations

    (J^T J + lam D) s = -J^T R,      D = diag(J^T J) (floored),

(``lam`` starts at ``1e-2``) with :class:`optimize.paper.linalg.SPDSolver`
(banded Cholesky on strips, SuperLU otherwise),
accepting the step when the gain ratio ``rho`` (actual / predicted decrease of
``E``) is positive (then ``lam`` shrinks by Nielsen's rule), otherwise ``lam``
grows and the system is solved again.  After every iteration ``w1`` and ``w2``
are halved, so the angle terms dominate more and more and the constraints
become exact.  Near-singular systems: see :mod:`optimize.paper.linalg`.

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

from ..mesh import Mesh
from ..result import OptimizeResult
from ..tolerances import DEFAULT, Tolerances
from .linalg import SPDSolver
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


def _rows(p: Problem, x: np.ndarray, w1: float, w2: float, foot=None, jac: bool = True):
    """Stacked weighted residual ``R`` (and Jacobian ``J`` on the free coordinates).

    foot : closeness footpoints ``(Y, N)``, fixed during one iteration.
    """
    if jac:
        c, A, _ = p.constraints(x, weighted=True)
        rs, Js = [c], [A]
    else:
        rs, Js = [p.constraints(x, weighted=True, jac=False)], []
    if w1 > 0:
        f, K = p.fairness(x)
        rs.append(np.sqrt(w1) * f)
        Js.append(np.sqrt(w1) * K)
    if w2 > 0:
        r = p.closeness(x, foot, jac=jac)
        rs.append(np.sqrt(w2) * (r[0] if jac else r))
        if jac:
            Js.append(np.sqrt(w2) * r[1])
    R = np.concatenate(rs)
    return (R, sp.vstack(Js, format="csr")) if jac else R


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
    if score <= stop_at:
        run.status, run.message = "converged", f"the input already satisfies the tolerances ({p.describe(m)})"
    while run.status == "max_iter" and run.nit < max_iter:
        ti = time.perf_counter()
        foot = p.footpoints(x) if w2 > 0 else None
        R, J = _rows(p, x, w1, w2, foot)
        E = float(R @ R)
        N = (J.T @ J).tocsr()
        g = J.T @ R
        d = N.diagonal()
        D = sp.diags(np.maximum(d, 1e-9 * max(float(d.max(initial=0.0)), 1.0)))
        tm["assemble"] += time.perf_counter() - ti
        accepted, tries, how = False, 0, "lu"
        while not accepted and tries < TRIES and lam <= LAM_MAX:
            tries += 1
            ts = time.perf_counter()
            s, how = solver.solve(N + lam * D, -g)
            tm["solve"] += time.perf_counter() - ts
            xn = p.step(x, s)
            ta = time.perf_counter()
            Rn = _rows(p, xn, w1, w2, foot, jac=False)
            tm["assemble"] += time.perf_counter() - ta
            En = float(Rn @ Rn)
            pred = float(-2 * (g @ s) - s @ (N @ s))
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
            fairness: float = 1e-3, closeness: float = 1e-2, tol: Tolerances = DEFAULT,
            max_iter: int = 200, callback=None, mu: float | None = None) -> OptimizeResult:
    """Run the penalty method on ``mesh`` (unchanged) and return an :class:`OptimizeResult`.

    Parameters are those of :func:`optimize.paper.run_paper_method`; ``mu`` is
    the weight of the strip determinants (default 1 for ``strip``, else 0).
    """
    t0 = time.perf_counter()
    p = Problem(mesh, target, reference=reference, fixed=fixed, fairness=fairness,
                closeness=closeness, tol=tol, mu=mu)
    run = run_penalty(p, p.x0(), max_iter=max_iter, callback=callback)
    run.timings["total"] = time.perf_counter() - t0
    return p.result(run.x, status=run.status, nit=run.nit, history=run.history, timings=run.timings,
                    method="penalty", message=run.message)
