"""The paper's practice: the penalty method first, then SQP; and the dispatcher.

``hybrid`` runs :func:`optimize.solvers.paper.penalty.run_penalty` until the worst
tested defect is within ``switch`` times its tolerance (default 1: the
tolerances themselves), it stalls, or it used ``penalty_iter`` iterations;
then :func:`optimize.solvers.paper.sqp.run_sqp` continues with the remaining budget,
minimizing the objective with the weights as given (``w1 f_fair + w2
f_close``, not the penalty's halved ones) subject to the constraints, and
returns its multipliers.  SQP never returns an iterate outside the
tolerances once it had one inside, so the hybrid result is at least as
exact as the penalty result.  A larger ``switch`` (e.g. 100) hands over
earlier, as the paper describes ("penalty to get near"); it used to converge
less often (11 of the 21 runs of ``benchmarks/bench_paper.py --sweep``),
because a Newton-KKT step pursuing a far-away optimum of the objective left
the constraints faster than it restored them; since SQP's proximal weight
grows after any step that leaves the constraints worse
(:mod:`optimize.solvers.paper.sqp`) it converges on all 21, taking more iterations.  Both phases use the determinant
rows on quad meshes (``mu = 1``, :func:`optimize.terms.problem.default_mu`).
The history holds both phases (``entry["phase"]``).
"""
from __future__ import annotations

import time

from ...errors import ConfigError
from ...mesh import Mesh
from ...options import DEFAULTS
from ...result import OptimizeResult
from ...tolerances import DEFAULT, Tolerances
from .cache import problem_for
from .penalty import penalty, run_penalty
from .sqp import KKT_PATIENCE, KKT_TOL, check_hessian, run_sqp, sqp

METHODS = ("penalty", "sqp", "hybrid")


def hybrid(mesh: Mesh, target: str = "pq", *, reference: Mesh | None = None, fixed=None,
           fairness: float = DEFAULTS.fairness, closeness: float = DEFAULTS.closeness, tol: Tolerances = DEFAULT,
           max_iter: int = DEFAULTS.max_iter, callback=None, mu: float | None = None, switch: float = 1.0,
           penalty_iter: int = 30, kkt_tol: float = KKT_TOL, kkt_patience: int = KKT_PATIENCE,
           hessian: str = "gauss-newton") -> OptimizeResult:
    """Penalty then SQP on ``mesh`` (unchanged); parameters as :func:`run_paper_method`."""
    t0 = time.perf_counter()
    with problem_for(mesh, target, reference=reference, fixed=fixed, fairness=fairness,
                     closeness=closeness, tol=tol, mu=mu, method="hybrid") as p:
        first = run_penalty(p, p.x0(), max_iter=min(penalty_iter, max_iter), callback=callback,
                            stop_at=switch)
        second = run_sqp(p, first.x, max_iter=max(max_iter - first.nit, 0), callback=callback,
                         kkt_tol=kkt_tol, kkt_patience=kkt_patience, first_iteration=first.nit,
                         hessian=check_hessian(hessian))
        timings = {f"penalty_{k}": v for k, v in first.timings.items()}
        timings.update({f"sqp_{k}": v for k, v in second.timings.items()})
        timings["total"] = time.perf_counter() - t0
        message = f"hybrid: {first.nit} penalty iterations ({first.status}), then {second.message}"
        status = second.status
        if max_iter - first.nit <= 0 and status == "max_iter":
            message = f"hybrid: max_iter={max_iter} used by the penalty phase ({first.message})"
        return p.result(second.x, status=status, nit=first.nit + second.nit,
                        history=first.history + second.history, timings=timings, method="hybrid",
                        message=message, multipliers=second.multipliers)


def run_paper_method(mesh: Mesh, target: str = "pq", method: str = "hybrid", *,
                     reference: Mesh | None = None, fixed=None, glide_boundary: bool = False,
                     fairness: float = DEFAULTS.fairness, closeness: float = DEFAULTS.closeness, tol: Tolerances = DEFAULT,
                     max_iter: int = DEFAULTS.max_iter, callback=None, **options) -> OptimizeResult:
    """Run one of the paper's methods; same keywords as ``optimize.optimize_mesh``.

    mesh : Mesh (never modified).  target : "pq" | "conical" | "circular" | "strip".
    method : "penalty" | "sqp" | "hybrid".
    reference : Mesh or None (the input).  fixed : None | "boundary" | "corners" | (k,) int.
    glide_boundary : not supported by the paper's methods (ConfigError when True).
    fairness, closeness : weights ``w1, w2`` (the penalty method halves them every iteration).
    tol : Tolerances.  max_iter : iteration budget.  callback : ``callback(entry: dict)``.
    options : method extras: ``mu`` (determinant weight; default
        :func:`optimize.terms.problem.default_mu`), ``kkt_tol``,
        ``kkt_patience``, ``hessian`` (sqp, hybrid), ``switch`` and
        ``penalty_iter`` (hybrid).

    Returns :class:`OptimizeResult` (``multipliers`` filled by sqp and hybrid).
    Raises :class:`ConfigError` for an unknown method/target/option, MeshError for a
    mesh the target cannot use (``strip`` needs one row of quads).
    """
    if method not in METHODS:
        raise ConfigError(f"method: {method!r} is not one of the paper's methods {METHODS}")
    if glide_boundary:
        raise ConfigError("glide_boundary: True is not supported by the paper's methods "
                          f"({method}); use method='default' or fix the boundary")
    sqp_opts = {"mu", "kkt_tol", "kkt_patience", "hessian"}
    allowed = {"penalty": {"mu"}, "sqp": sqp_opts,
               "hybrid": sqp_opts | {"switch", "penalty_iter"}}[method]
    unknown = sorted(set(options) - allowed)
    if unknown:
        raise ConfigError(f"option(s) {unknown} not known to method {method!r}, expected some of "
                          f"{sorted(allowed)}")
    if int(max_iter) < 0:
        raise ConfigError(f"max_iter: {max_iter!r}, expected a non-negative integer")
    fn = {"penalty": penalty, "sqp": sqp, "hybrid": hybrid}[method]
    return fn(mesh, target, reference=reference, fixed=fixed, fairness=fairness, closeness=closeness,
              tol=tol, max_iter=int(max_iter), callback=callback, **options)
