"""Constrained fairing: exact, fair and close at once.

The guided solve (:mod:`optimize.solvers.guided`) reaches the constraints with soft
fairness and closeness weights that fade and are dropped, so its result minimizes
nothing in particular: closer and fairer meshes satisfy the same constraints.  This
phase starts from its converged iterate and minimizes

    E(x) = w_f |K (v - v_in)|^2 + w_c |(v - y) . n|^2 (+ the convexity / edge-floor hinges)

subject to every constraint row of the formulation (and the boundary gliding rows) kept
exact: sequential quadratic programming with Gauss-Newton Hessians.  ``K`` is the
fairness matrix (second differences along the mesh polylines), applied to the
displacement from the input ``v_in``: fairness relative to the input, which keeps its
curvature and removes only what the constraints add (creases along mesh lines); the
closeness is the tangent-plane term with footpoints on the reference renewed every
iteration.  The weights are ``w_f = b``, ``w_c = 1 - b`` with the balance
``b = fairness / (fairness + closeness)`` of the run's two weights (the one knob:
only their ratio matters here, since the constraints are exact).  Beside the tangent-plane
row, a vertex whose closest point lies on the reference's boundary gets the in-plane part
of its distance (:func:`off_surface`; without it boundary vertices slid off the surface:
tube conical 5.2% of the diagonal), and a weak anchor ``ANCHOR |v - v_in|^2`` stops the
tangential drift (without it quads collapsed on the canopy).

One iteration solves the regularized KKT system

    [[H + mu I, A^T], [A, -EPS I]] [dx; lam] = [-g; -phi]

(``H, g``: Gauss-Newton Hessian and gradient of ``E``; ``A, phi``: the constraints'
Jacobian and rows; SuperLU), then projects the trial point back onto the constraints with
up to ``PROJECT`` corrections from the same factorization (``A dc = -phi(trial)``,
smallest in the ``H`` metric).  A trial is accepted when it lowers ``E`` (footpoints of
the linearization), keeps the constraint rows within ``max(start, FEASIBLE)`` and folds
no face (``convexity.FoldCheck`` against the input); otherwise ``mu`` grows tenfold.  The
phase stops when ``E`` falls by less than ``STOP`` relatively, and keeps its result
only when every measured defect is within tolerance (otherwise the guided iterate
stands and the message says so).
"""
from __future__ import annotations

import logging
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..mesh import measures
from ..proximity.footpoints import Footpoints
from ..terms import convexity, edgefloor
from ..terms import glide as glide_mod
from ..terms.closeness import closeness_terms
from ..terms.fairness import fairness_matrix
from ..terms.formulation import Formulation
from ..tolerances import Tolerances
from . import guided

log = logging.getLogger(__name__)

MAX_ITER = 40
EPS = 1e-10  # the KKT's dual regularization: redundant constraint rows stay solvable
PROJECT = 8  # corrections back onto the constraints per trial
FEASIBLE = 1e-10  # constraint rows (normalized coordinates) always accepted up to this
STOP = 1e-4  # relative decrease of E below which the phase ends
MU_START, MU_MIN, MU_MAX = 1e-4, 1e-10, 1e4
ANCHOR = 0.01  # weight of the displacement |v - v_in|^2 beside the tangent-plane closeness (relative)
HINGE = 10.0  # weight of the one-sided convexity / edge-floor rows in E


def _degenerate_faces(form: Formulation, x: np.ndarray, x_in: np.ndarray) -> int:
    """How many faces of the iterate ``x`` are degenerate against the input ``x_in``
    (:func:`optimize.mesh.measures.degenerate`: a shrunk edge or a straight corner)."""
    L = form.layout
    d = measures.degenerate(form.mesh, L.view(x, "vertices"), L.view(x_in, "vertices"))
    return int(d["shrunk_edges"]["count"] + d["straight_corners"]["count"])


def off_surface(V: np.ndarray, Y: np.ndarray, N: np.ndarray) -> tuple[np.ndarray, sp.csr_matrix]:
    """The in-plane part of the distance to the reference, ``r (n,)`` and ``J (n, 3n)``: zero for a
    vertex above the reference's interior (its closest point ``y`` is then straight below), the
    distance beyond the reference's boundary otherwise, so that with the tangent-plane row it
    makes up the whole distance ``|v - y|`` (boundary vertices cannot slide off the surface)."""
    D = V - Y
    T = D - np.einsum("ij,ij->i", D, N)[:, None] * N
    r = np.linalg.norm(T, axis=1)
    U = np.where((r > 1e-9)[:, None], T / np.maximum(r, 1e-300)[:, None], 0.0)
    n = len(V)
    J = sp.csr_matrix((U.ravel(), (np.repeat(np.arange(n), 3), np.arange(3 * n))), shape=(n, 3 * n))
    return np.where(r > 1e-9, r, 0.0), J


def balance(fairness: float, closeness: float) -> tuple[float, float]:
    """``(w_f, w_c)``: the run's fairness and closeness weights as a balance summing to 1."""
    total = float(fairness) + float(closeness)
    return (float(fairness) / total, float(closeness) / total) if total > 0 else (0.0, 0.0)


def refine(form: Formulation, run: guided.RunState, x_in: np.ndarray, *, ref, glide: guided.Glide | None,
           convex: guided.Convex | None, tol: Tolerances, fairness: float, closeness: float,
           max_iter: int = MAX_ITER, callback=None, extra=None, phase: str = "fairing") -> guided.RunState:
    """The constrained fairing phase from a converged ``run`` (normalized coordinates);
    ``x_in (layout.size,)`` is the start of the run (its vertices: the input).  Returns ``run``
    with the phase's iterate, iterations and history added (``"phase": phase`` in each
    entry, ``timings[phase]``), or ``run`` unchanged when there is nothing to do or the
    phase could not keep every tolerance (the message then says so).
    extra : None, or ``extra(x) -> (r (p,), J (p, layout.size))``: weighted rows added to ``E``
    (the rationalization's congruence rows, :mod:`optimize.solvers.rationalize`)."""
    wf, wc = balance(fairness, closeness)
    if run.status != "converged" or (wf == 0 and wc == 0 and extra is None) or max_iter <= 0:
        return run
    t0 = time.perf_counter()
    L = form.layout
    fixed = form.spec.fixed
    free = np.ones(L.size, dtype=bool)
    free[L.index("vertices")[fixed].ravel()] = False
    free_idx = np.nonzero(free)[0]
    S = sp.csr_matrix((np.ones(len(free_idx)), (free_idx, np.arange(len(free_idx)))),
                      shape=(L.size, len(free_idx)))
    K = guided._embed(fairness_matrix(form.mesh), L.size)
    Kin = K @ x_in
    vi = L.index("vertices").ravel()
    P = sp.csr_matrix((np.ones(len(vi)), (np.arange(len(vi)), vi)), shape=(len(vi), L.size))
    use_close = ref is not None and wc > 0
    finder = Footpoints(ref, guided.FOOT_MARGIN, compiled=False) if use_close else None
    V0 = convex.V0 if convex is not None else L.view(x_in, "vertices").copy()
    folds = convexity.FoldCheck(form.mesh, V0, tol.fold)

    def constraints(x, gfoot):
        phi, A = form.terms(x)
        if glide is None:
            return phi, A
        rg, Jg = glide_mod.terms(x, L, glide.vertices, glide.curve, gfoot)
        return np.concatenate([phi, rg]), sp.vstack([A, Jg], format="csr")

    def energy(x, foot):
        """Weighted residual of E and its Jacobian (all columns)."""
        rs, Js = [], []
        if wf > 0:
            rs.append(np.sqrt(wf) * (K @ x - Kin))
            Js.append(np.sqrt(wf) * K)
        if use_close:
            V = L.view(x, "vertices")
            Jc, rc = closeness_terms(V, ref, *foot)
            rs.append(np.sqrt(wc) * rc)
            Js.append(np.sqrt(wc) * guided._embed(Jc, L.size))
            rt, Jt = off_surface(V, *foot)
            rs.append(np.sqrt(wc) * rt)
            Js.append(np.sqrt(wc) * guided._embed(Jt, L.size))
        if wc > 0 and ANCHOR > 0:
            rs.append(np.sqrt(wc * ANCHOR) * (P @ x - P @ x_in))
            Js.append(np.sqrt(wc * ANCHOR) * P)
        if glide is not None and len(glide.edges):
            re, Je = edgefloor.terms(x, L, glide.edges, glide.floor)
            rs.append(np.sqrt(HINGE) * re)
            Js.append(np.sqrt(HINGE) * Je)
        if convex is not None:
            rv, Jv = convexity.terms(x, L, form.mesh, convex.corners, convex.floor)
            rs.append(np.sqrt(HINGE) * rv)
            Js.append(np.sqrt(HINGE) * Jv)
        if extra is not None:
            rx, Jx = extra(x)
            rs.append(rx)
            Js.append(Jx)
        return np.concatenate(rs), sp.vstack(Js, format="csr")

    def glide_foot(x):
        return glide.curve.closest(L.view(x, "vertices")[glide.vertices]) if glide is not None else None

    x = run.x.copy()
    folded0 = folds.faces(L.view(x, "vertices"))
    history, mu, nit, reason = [], MU_START, 0, "the energy stopped falling"
    theta_cap = None
    while nit < max_iter:
        t_it = time.perf_counter()
        foot = finder.closest(L.view(x, "vertices")) if use_close else None
        gfoot = glide_foot(x)
        r, Je = energy(x, foot)
        phi, A = constraints(x, gfoot)
        theta0 = float(np.abs(phi).max(initial=0.0))
        if theta_cap is None:
            theta_cap = max(theta0, FEASIBLE)
        E0 = float(r @ r)
        Jf, Af = Je @ S, (A @ S).tocsr()
        H = (Jf.T @ Jf).tocsr()
        g = Jf.T @ r
        m = Af.shape[0]
        accepted = False
        while not accepted and mu <= MU_MAX:
            kkt = sp.bmat([[H + sp.identity(H.shape[0]) * mu, Af.T], [Af, sp.identity(m) * -EPS]], format="csc")
            try:
                lu = spla.splu(kkt)
            except RuntimeError as exc:  # exactly singular: more damping
                log.info("fairing iteration %d: %s; raising the damping", nit + 1, exc)
                mu *= 10
                continue
            n_free = H.shape[0]
            sol = lu.solve(np.concatenate([-g, -phi]))
            xt = x + S @ sol[:n_free]
            pt, _ = constraints(xt, glide_foot(xt))
            for _ in range(PROJECT):  # the chord method: the factor at x, the rows at the trial
                if not np.all(np.isfinite(pt)) or np.abs(pt).max(initial=0.0) <= theta_cap:
                    break
                c = lu.solve(np.concatenate([np.zeros(n_free), -pt]))
                xc = xt + S @ c[:n_free]
                pc, _ = constraints(xc, glide_foot(xc))
                if not np.abs(pc).max(initial=0.0) < 0.5 * np.abs(pt).max(initial=0.0):
                    break  # not converging: the step was too long
                xt, pt = xc, pc
            theta = float(np.abs(pt).max(initial=np.inf if not len(pt) else 0.0)) if np.all(np.isfinite(pt)) \
                else np.inf
            rt, _ = energy(xt, foot)
            Et = float(rt @ rt) if np.all(np.isfinite(rt)) else np.inf
            if Et < E0 and theta <= theta_cap and not (folds.faces(L.view(xt, "vertices")) & ~folded0).any():
                accepted = True
            else:
                mu *= 10
        if not accepted:
            reason = f"no step lowers the energy with the constraints kept (damping {MU_MAX:g})"
            break
        nit += 1
        step = float(np.abs(xt - x)[L.slice("vertices")].max())
        x = xt
        mu = max(mu / 10, MU_MIN)
        entry = {"iteration": run.nit + nit, "phase": phase, "step": step, "mu": mu, "energy": Et,
                 "constraint_residual": theta, "seconds": time.perf_counter() - t_it}
        entry.update({k: float(d.max(initial=0.0)) for k, d in guided.measured(form, x, glide).items()})
        entry["folded"] = int(folds.faces(L.view(x, "vertices")).sum())  # as every guided entry has it
        history.append(entry)
        log.info("%s iteration %d: energy %.6g, constraints %.3g, step %.3g", phase, nit, Et, theta, step)
        if callback is not None:
            callback(entry)
        if E0 - Et <= STOP * E0:
            break
    else:
        reason = f"stopped after {max_iter} iterations"
    defects = guided.measured(form, x, glide)
    score = guided._score(defects, tol)
    timings = dict(run.timings)
    timings[phase] = timings.get(phase, 0.0) + time.perf_counter() - t0
    slivers = _degenerate_faces(form, x, x_in) - _degenerate_faces(form, run.x, x_in)
    if score > 0 or not nit or slivers > 0:
        note = (f"; the {phase} phase kept no step ({reason})" if not nit else
                f"; the {phase} phase was dropped: after {nit} iterations a defect was 10^{score:.2f} "
                f"of its tolerance" if score > 0 else
                f"; the {phase} phase was dropped: it left {slivers} more degenerate face(s) (a shrunk edge "
                "or a straight corner)")
        return guided.RunState(x=run.x, status=run.status, message=run.message + note, nit=run.nit,
                               history=run.history, timings=timings, defects=run.defects)
    message = (f"{run.message}, then {nit} {phase} iteration(s) with every constraint kept ({reason})")
    return guided.RunState(x=x, status="converged", message=message, nit=run.nit + nit,
                           history=run.history + history, timings=timings,
                           defects={k: float(d.max(initial=0.0)) for k, d in defects.items()})
