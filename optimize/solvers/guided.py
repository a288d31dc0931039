"""Regularized Gauss-Newton on quadratic constraints ("guided projection").

After Tang, Sun, Gomes, Wallner, Pottmann, "Form-finding with polyhedral
meshes made simple" (SIGGRAPH 2014): every constraint is at most quadratic in
the unknowns (positions plus auxiliary normals, axes, centres), so its
linearization is cheap and accurate.  One iteration solves

    min_dx |phi + J dx|^2 + w_f |K (x + dx)|^2 + w_c |r_c + C dx|^2
           + |r_g + G dx|^2 + mu |dx|^2

Rows with wide stencils (fairness ``a - 2v + b``) would fill the sparse
factor.  Each is written as a sum of ``P`` parts that stay within one face
(``(a - v) + (b - v)``; one part per corner) and enters the matrix through
the majorant ``(r + sum_k J_k dx)^2 <= sum_k (r / sqrt(P) + sqrt(P) J_k dx)^2``:
same value and gradient at ``dx = 0``, no fill, so the step is a
majorize-minimize descent step for those rows while the constraints keep
exact Gauss-Newton rows.  (The conical angle balance could be split the
same way, one part per corner; that was measured to stall in local minima
or converge only linearly, so it stays exact: ``split_terms(exact_angles=True)``.)

(constraints ``phi``; fairness ``K``; tangent-plane closeness ``r_c`` with
footpoints recomputed at ``x``; boundary gliding ``r_g``; Levenberg-Marquardt
damping ``mu``) as one sparse SPD system.  A step is accepted when it lowers
that objective (otherwise ``mu`` grows and the system is solved again; an accepted
step's gain ratio sets the next ``mu``, see ``solve``); the
soft weights ``w_f, w_c`` are halved every iteration (``w_f`` also scaled by the
worst defect over ``FAR``: a mesh nearly there is not faired away), as in the paper's
penalty method, so that the constraints become exact while the first steps
stay fair and close; within a factor 100 of the tolerances (or after ten
halvings) they are dropped and the damped Gauss-Newton iteration finishes
quadratically.

Everything runs in normalized coordinates (centred, unit mean edge length):
the weights mean the same at every scale.  The run stops on tests: every
measured defect within tolerance (converged), no progress for ``patience``
iterations or no step lowering the objective (stalled), non-finite values
(diverged, the last good iterate is kept), or ``max_iter``.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..linalg.normal import NormalSolver, Shifted, SolveError
from ..mesh import measures
from ..proximity.curve import BoundaryCurve
from ..proximity.footpoints import Footpoints
from ..proximity.surface import Reference
from ..terms import convexity, edgefloor
from ..terms import glide as glide_mod
from ..terms.closeness import closeness_terms
from ..terms.fairness import fairness_matrix, fairness_matrix_parts
from ..terms.formulation import Formulation
from ..tolerances import Tolerances

log = logging.getLogger(__name__)

MU_START, MU_MIN, MU_MAX = 1e-3, 1e-12, 1e8
FOOT_MARGIN = 0.1  # footpoint candidates renewed for vertices that moved this far (mean edge lengths;
#                    0.3 made the candidate sets of a 10k-face dome too large: 1.1 s against 0.15 s)
STAY = 1.0  # damping floor / fairness weight while the soft terms act
FAST, SHRINK = 30.0, 3.0
"""Damping divisors after a very well (rho > 0.9) and a well (rho > 0.75) predicted step.
Measured in one run (iterations; railway station level 3 conical / halftunnel conical with
node axes / 10k-face conical dome / remeshed dome, gliding boundary / 2,500-face circular
dome): FAST 30: 4 / 66 / 8 / 104 / 6; FAST 3: 7 / 66 / 10 / 104 / 7; FAST 10: 5 / 111 / 8 /
not converged in 200 / 6; FAST 100: 4 / 111 / 8 / not converged / 5; the earlier
mu/10-and-2mu rule: - / 127 / 8 / not converged / 6.  The hard cases are sensitive to the
path, so these figures are not a smooth function of the settings."""


FAR = 0.1
"""The fairness weight acts in full while the worst target defect (planarity, or the
target's angle defect in radians) is at least FAR, and in proportion below it: the
fairing is there to steer large corrections, and a mesh that is nearly there needs
only a small move.  Measured (default weights, max distance to the input / bbox
diagonal; roughness = mean second difference / mean edge length, input -> result),
weight in full / FAR 1e-2 / FAR 0.1: halftunnel PQ (input planar to 2.4e-5) 2.4e-3
(roughness 0.249 -> 0.221, 6 iterations) / 2.2e-5 / 2.3e-6 (0.249 -> 0.249, 1
iteration; libigl 5e-7); halftunnel circular 3.5e-3 / 3.0e-3 / 2.5e-3; conical 3.0e-3 /
2.0e-3 / 1.9e-3; conjugate900+noise 6.2e-3 / 5.5e-3 / 3.8e-3 (roughness 0.381 -> 0.063 /
0.118 / 0.261); 2,500-face dome circular 3.3e-4 in each.  A fair step metric ``|K dx|^2``
beside the damping (instead of a weight) kept every input's roughness but lost the fast
convergence (halftunnel conical / circular, conjugate900+noise: max_iter at 200)."""


@dataclass
class Glide:
    """Boundary gliding: ``vertices (b,)`` kept on ``curve`` (normalized coordinates)."""

    vertices: np.ndarray
    curve: BoundaryCurve
    edges: np.ndarray  # (e, 2) boundary edges at gliding vertices, kept above ``floor (e,)``
    floor: np.ndarray


@dataclass
class Convex:
    """Convexity kept (:mod:`optimize.terms.convexity`): hinge rows on ``corners (k,)``
    above ``floor (k,)``, and no accepted step may fold a face convex at ``V0 (n, 3)``."""

    corners: np.ndarray
    floor: np.ndarray
    V0: np.ndarray


@dataclass
class RunState:
    """What :func:`solve` returns: the final unknowns and how the run went."""

    x: np.ndarray
    status: str
    message: str
    nit: int
    history: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    defects: dict = field(default_factory=dict)


DEFECTS = {"planarity": measures.planarity, "conical": measures.conical_defect,
           "circular": measures.circular_defect}


def target_defects(form: Formulation, V: np.ndarray) -> dict[str, np.ndarray]:
    """The measured defects the target must bring under tolerance, ``name -> (k,)``: those the
    problem description tests (``form.spec.tests``)."""
    return {name: DEFECTS[name](form.mesh, V) for name in form.spec.tests}


def measured(form: Formulation, x: np.ndarray, glide: Glide | None) -> dict[str, np.ndarray]:
    """Every defect the run is held to at ``x``: the target's (:func:`target_defects`), the node
    axes' (``form.axis_defects``) and, with a gliding boundary, the distance to the boundary
    curve and the edges' shortfall below their floor (``glide``, ``short_edge``)."""
    V = form.layout.view(x, "vertices")
    out = target_defects(form, V)
    out.update(form.axis_defects(x))
    if glide is not None:
        Y, _ = glide.curve.closest(V[glide.vertices])
        out["glide"] = np.linalg.norm(V[glide.vertices] - Y, axis=1)  # mean edge length is 1
        if len(glide.edges):
            out["short_edge"] = edgefloor.shortfall(V, glide.edges, glide.floor)
    return out


def _score(defects: dict, tol: Tolerances) -> float:
    """log10 of the worst defect / tolerance ratio (<= 0 means converged).

    Each defect is held to ``tol.for_defect(name)`` (``glide``, ``short_edge`` to the
    planarity tolerance, ``node_cone``, ``beam`` to the conical one: ``tolerances.HELD_TO``).
    """
    worst = [max(float(d.max(initial=0.0)), 1e-300) / tol.for_defect(k) for k, d in defects.items()]
    return float(np.log10(max(worst)))


def _embed(M: sp.spmatrix, n_cols: int) -> sp.csr_matrix:
    """Rows over the leading ``vertices`` block, widened to ``n_cols`` columns."""
    M = M.tocsr()
    return sp.csr_matrix((M.data, M.indices, M.indptr), shape=(M.shape[0], n_cols))


def normal_equations(J: sp.csr_matrix, wide_parts: list, r: np.ndarray,
                     S: sp.csr_matrix | None) -> tuple[sp.csr_matrix, np.ndarray]:
    """``(J_f^T J_f + sum_p P sum_k J_k^T J_k, g)`` of one iteration, over the free unknowns.

    J : (m, size) the exact rows; wide_parts : per majorized term its ``P`` parts ``J_k``
    (each (m_p, size)); r : the stacked residual, ``J``'s rows first, then each wide term's
    rows (its gradient rows are the sum of its parts); S : (size, k) the free unknowns'
    selection, None when every unknown is free.  The matrix is one product ``B^T B`` of the
    rows stacked (``sqrt(P) J_k`` for the parts), not a sum of products: one sparse product
    and no intermediate sums (at 300k faces each sum was a full copy of the matrix)."""
    m = J.shape[0]
    g = J.T @ r[:m]
    rows = [J]
    for p in wide_parts:
        Jw = sum(p[1:], p[0])
        g += Jw.T @ r[m:m + Jw.shape[0]]
        m += Jw.shape[0]
        rows += [np.sqrt(len(p)) * Jk for Jk in p]
    B = sp.vstack(rows, format="csr")
    del rows
    if S is not None:
        B = B @ S
        g = S.T @ g
    Bt = B.T.tocsr()  # one transpose; B.T @ B would convert B and then the product
    return Bt @ B, g


def solve(form: Formulation, x0: np.ndarray, *, ref: Reference | None,
          glide: Glide | None, tol: Tolerances,
          max_iter: int, callback=None, backend: str = "auto", patience: int = 10,
          convex: Convex | None = None, far: float | None = FAR,
          decay: float = 0.5, finish: float = 2.0,
          soft_iters: int = 10) -> RunState:
    """Run the iteration from ``x0 (layout.size,)`` (normalized coordinates).

    The problem is ``form``'s description (``form.spec``): its rows, its fixed vertices
    (whose coordinates are not unknowns) and its energies (the fairness and closeness
    weights).  ref : the closeness reference in normalized coordinates (None: no closeness).
    glide, convex : the data of the description's ``glide`` and ``convexity`` terms.
    far : the fairness weight is scaled by ``min(1, worst defect / far)`` (see ``FAR``;
        None: always in full, the earlier behaviour).
    decay : factor applied to the soft weights after each iteration; they are
        dropped once the worst defect is within ``10**finish`` of its tolerance
        or after ``soft_iters`` iterations (then ``0.5**10`` of their start).
    The damping follows an accepted step's gain ratio ``rho`` (actual decrease of
    the objective over the decrease the linearized, majorized model predicts):
    ``mu / FAST`` when ``rho > 0.9``, ``mu / SHRINK`` when ``rho > 0.75``, else
    unchanged (never below the floor); see ``FAST`` for the measurements.
    callback : called with each iteration's history dict (observes only).
    convex : keep convex corners convex: hinge rows, and a trial step that folds a face
        (``measures.folded_faces`` against ``convex.V0``) is rejected like a step that
        does not lower the objective (the damping grows), so every accepted iterate is
        fold-free.  History entries carry ``folded`` (faces folded at that iterate) either way.
    """
    t_start = time.perf_counter()
    L = form.layout
    fixed = form.spec.fixed
    fairness, closeness = form.spec.energies.fairness, form.spec.energies.closeness
    timings = {"closest": 0.0, "assemble": 0.0, "solve": 0.0, "measure": 0.0}
    free = np.ones(L.size, dtype=bool)
    free[L.index("vertices")[fixed].ravel()] = False
    free_idx = np.nonzero(free)[0]
    S = sp.csr_matrix((np.ones(len(free_idx)), (free_idx, np.arange(len(free_idx)))),
                      shape=(L.size, len(free_idx)))
    all_free = len(free_idx) == L.size
    blocks = form.face_blocks() if backend == "eliminate" else None
    if blocks is not None:
        pos = np.full(L.size, -1, dtype=np.int64)
        pos[free_idx] = np.arange(len(free_idx))
        blocks = np.where(blocks >= 0, pos[np.maximum(blocks, 0)], -1)
    solver = NormalSolver(backend, blocks)
    K = _embed(fairness_matrix(form.mesh), L.size)
    K1, K2 = (_embed(k, L.size) for k in fairness_matrix_parts(form.mesh))
    wf, wc = float(fairness), float(closeness)
    use_close = ref is not None and wc > 0
    finder = None
    if use_close:
        # exact closest points, candidate triangles kept between iterations (vertices move
        # little): 10k-face conical dome 0.93 s of closest-point queries -> 0.26 s.  The NumPy
        # path: the compiled one (0.14 s) costs 0.4-0.9 s of numba load in a fresh process.
        finder = Footpoints(ref, FOOT_MARGIN, compiled=False)

    def residuals(x, foot, gfoot):
        """Stacked weighted residual, Jacobian of the exact rows, Jacobian of the
        majorized rows (fairness, wide constraint stencils) and the constraints."""
        phi, J, wide = form.split_terms(x)
        rs, Js = [phi], [J]
        if wf > 0:
            sf = np.sqrt(wf * fscale[0])
            wide = wide + [(sf * (K @ x), None, [sf * K1, sf * K2])]
        if use_close and wc > 0:
            Jc, rc = closeness_terms(L.view(x, "vertices"), ref, *foot)
            rs.append(np.sqrt(wc) * rc)
            Js.append(np.sqrt(wc) * _embed(Jc, L.size))
        if glide is not None:
            rg, Jg = glide_mod.terms(x, L, glide.vertices, glide.curve, gfoot)
            rs.append(rg)
            Js.append(Jg)
            if len(glide.edges):
                re, Je = edgefloor.terms(x, L, glide.edges, glide.floor)
                rs.append(re)
                Js.append(Je)
        if convex is not None:
            rv, Jv = convexity.terms(x, L, form.mesh, convex.corners, convex.floor)
            rs.append(rv)
            Js.append(Jv)
        rw = [w[0] for w in wide]
        phi_all = np.concatenate([phi] + [w[0] for w in wide if w[1] is not None])
        return np.concatenate(rs + rw), sp.vstack(Js, format="csr"), [w[2] for w in wide], phi_all

    def measure(x):
        tm = time.perf_counter()
        out = measured(form, x, glide)
        timings["measure"] += time.perf_counter() - tm
        return out

    x = x0.copy()
    # While the soft terms act, the damping stays at least the fairness weight: in
    # directions no constraint sees, the (majorized, so only partial) fairing step is
    # then at most about half a full one, and the mesh does not drift along the surface
    # every iteration.  Afterwards the floor is MU_MIN: smooth, global deformations
    # of large meshes have tiny eigenvalues and a larger damping would stall them.
    mu_floor = max(MU_MIN, STAY * float(fairness))
    defects = measure(x)
    target_keys = [k for k in ("planarity", "conical", "circular") if k in defects]
    score = best = _score(defects, tol)
    history: list[dict] = []
    status, message, nit, since_best, mu = None, "", 0, 0, MU_START
    folds_rejected = 0
    fscale = [1.0]  # fairness weight factor: the worst target defect / far (at most 1)
    folds = convexity.FoldCheck(form.mesh, L.view(x0, "vertices").copy() if convex is None else convex.V0,
                                tol.fold)
    if score <= 0:
        status, message = "converged", "the input already satisfies every tolerance"
    while status is None:
        if nit >= max_iter:
            status = "max_iter"
            message = f"stopped after {nit} iterations (max_iter) with worst defect/tolerance 10^{score:.2f}"
            break
        nit += 1
        t_it = time.perf_counter()
        if far is not None:
            fscale[0] = min(1.0, max(float(defects[k].max(initial=0.0)) for k in target_keys) / far)
            if wf > 0 or wc > 0:
                mu_floor = max(MU_MIN, STAY * float(fairness) * fscale[0])
        V = L.view(x, "vertices")
        tc = time.perf_counter()
        foot = finder.closest(V) if use_close and wc > 0 else None  # footpoints while the term acts
        gfoot = glide.curve.closest(V[glide.vertices]) if glide is not None else None
        timings["closest"] += time.perf_counter() - tc
        ta = time.perf_counter()
        r, J, wide_parts, phi = residuals(x, foot, gfoot)
        JtJ, g = normal_equations(J, wide_parts, r, None if all_free else S)
        del J, wide_parts  # the hinge rows come and go: PARDISO keeps the pattern they widened
        merit0 = float(r @ r)
        timings["assemble"] += time.perf_counter() - ta
        accepted, tries, broken = False, 0, 0
        while not accepted and mu <= MU_MAX:
            tries += 1
            ts = time.perf_counter()
            try:
                dx = solver.solve(Shifted(JtJ, mu), -g)
            except SolveError as exc:
                log.info("iteration %d: %s; raising the damping", nit, exc)
                timings["solve"] += time.perf_counter() - ts
                mu *= 10
                broken += 1
                continue
            timings["solve"] += time.perf_counter() - ts
            xn = x + S @ dx
            ta = time.perf_counter()
            rn, _, _, _ = residuals(xn, foot, gfoot)
            timings["assemble"] += time.perf_counter() - ta
            merit1 = float(rn @ rn)
            if convex is not None and np.isfinite(merit1) and merit1 < merit0 and \
                    folds.faces(L.view(xn, "vertices")).any():
                folds_rejected += 1
                mu *= 10  # a shorter step, closer to the linearization the hinge rows saw
                continue
            if np.isfinite(merit1) and merit1 < merit0:
                accepted = True
                # gain ratio: actual decrease over the decrease the (majorized) model predicts
                pred = -(2.0 * float(g @ dx) + float(dx @ (JtJ @ dx)))
                rho = (merit0 - merit1) / pred if pred > 0 else 0.0
                if rho > 0.9:
                    mu = max(mu / FAST, mu_floor)
                elif rho > 0.75:
                    mu = max(mu / SHRINK, mu_floor)
                elif rho < 0.25:  # a poorly predicted step keeps mu, raised to the floor if below
                    mu = max(mu, mu_floor)
            else:
                broken += not np.isfinite(merit1)
                mu *= 10
        if not accepted and broken == tries:
            status = "diverged"
            message = (f"iteration {nit}: every trial step failed or gave non-finite values "
                       f"({tries} tries up to damping {MU_MAX:g}); the last good iterate is kept")
            nit -= 1
            break
        if not accepted:
            status = "stalled"
            message = (f"iteration {nit}: no step lowers the objective even with damping {MU_MAX:g} "
                       f"(a local minimum; worst defect/tolerance 10^{score:.2f})")
            nit -= 1
            break
        step = float(np.abs(xn - x)[L.slice("vertices")].max())
        x = xn
        defects = measure(x)
        score = _score(defects, tol)
        entry = {"iteration": nit, "step": step, "mu": mu, "tries": tries, "objective": merit1,
                 "constraint_residual": float(np.abs(phi).max(initial=0.0)),
                 "fairness_weight": wf * fscale[0], "closeness_weight": wc,
                 "seconds": time.perf_counter() - t_it}
        for k, d in defects.items():
            entry[k] = float(d.max(initial=0.0))
            entry[k + "_mean"] = float(d.mean()) if d.size else 0.0
        entry["fairness"] = float(np.sum((K @ x) ** 2) / max(1, K.shape[0] // 3))
        entry["folded"] = int(folds.faces(L.view(x, "vertices")).sum())
        if foot is not None:
            entry["closeness"] = float(np.linalg.norm(V - foot[0], axis=1).max() / ref.bbox_diagonal)
        history.append(entry)
        log.info("iteration %d: %s", nit, {k: f"{v:.3g}" for k, v in entry.items() if isinstance(v, float)})
        if callback is not None:
            callback(entry)
        if score <= 0:
            status = "converged"
            message = f"every tolerance reached in {nit} iterations"
        elif score < best - 0.01:
            best, since_best = score, 0
        elif wf == 0 and wc == 0:  # progress is judged once the soft terms are gone
            since_best += 1
            if since_best >= patience:
                status = "stalled"
                message = (f"no progress in {patience} iterations (worst defect/tolerance "
                           f"10^{score:.2f}, best 10^{best:.2f})")
        if score < finish or nit >= soft_iters:  # plain damped Gauss-Newton converges fast
            wf = wc = 0.0
            mu_floor = MU_MIN
        wf *= decay
        wc *= decay
    timings["total"] = time.perf_counter() - t_start
    timings["factorizations"] = solver.factorizations
    timings["cg_iterations"] = solver.cg_iterations
    timings["fold_rejections"] = folds_rejected
    return RunState(x=x, status=status, message=message, nit=nit, history=history, timings=timings,
                    defects={k: float(d.max(initial=0.0)) for k, d in defects.items()})
