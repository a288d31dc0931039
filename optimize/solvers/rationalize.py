"""Rationalization: near-congruent panels pulled into exact classes, every constraint kept.

A roof of 640 panels of 640 shapes costs more than one of 160: a glass cutter
sets up once per shape.  After a converged solve this phase alternates

1. *clustering*: the faces within ``pull`` (model units) of each other at every
   corner after the best rigid fit (mirror images allowed) form a class
   (:func:`pull_classes`: the leader rule of :mod:`optimize.mesh.congruence`,
   the faces with the most near neighbours leading), each member's corners listed
   in the order matching its leader's;
2. *pulling*: the constrained fairing phase (:func:`optimize.solvers.fairing.refine`:
   SQP with every constraint row kept exact, no fold, no new degenerate face)
   minimizes ``WEIGHT |r|^2`` of the congruence rows (:mod:`optimize.terms.congruence`:
   every corner distance of a member against its class's mean) beside the run's
   fairness and closeness energies, and a one-sided row per vertex that keeps it within
   ``MARGIN`` of the closeness limit of the reference, and rows that keep the
   design's symmetries;

until the number of different faces within ``tol_mm`` (:func:`optimize.mesh.congruence.face_classes`,
the rule the glass order counts by) stops falling, or a round would move the
design further than ``limit`` (the largest distance to the reference, model
units): that round is dropped and the previous one stands.  The constraints are
exact at every accepted round (the SQP keeps them), so the result is as PQ /
conical as the solve's; a class the constraints do not allow to close stays apart.
"""
from __future__ import annotations

import logging
import time

import numpy as np
import scipy.sparse as sp

from ..mesh.congruence import TOLERANCE_MM, Classes, _ring_keys, face_classes, face_rings, ring_classes
from ..terms import congruence
from ..terms.fairness import roughness
from . import fairing, guided

log = logging.getLogger(__name__)

WEIGHT = 1e3
"""Weight of the congruence rows against the run's fairness + closeness balance (which sums to 1)."""
ROUNDS = 6
"""Cluster-then-pull rounds at most."""
ITERATIONS = 30
"""SQP iterations per round at most."""
MARGIN = 0.95
"""A vertex further than this fraction of the closeness limit from the reference is pulled back
(a one-sided row of the congruence rows' weight)."""


def pull_classes(mesh, V: np.ndarray, pull: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The classes to pull together: per corner count ``k``, ``(corners (q, k) int, label (q,) int)``
    of the faces in a class of two or more (within ``pull`` of its leader at every corner), each
    face's vertex indices in the order matching its leader's corners (reversed for the other hand).
    Leaders are the faces with the most others near them (invariant keys within ``2 pull``)."""
    from scipy.spatial import cKDTree

    out = []
    base = 0
    for faces, X in face_rings(mesh, V):
        k = X.shape[2]
        keys = _ring_keys(X, None, True)
        near = np.array([len(s) for s in cKDTree(keys).query_ball_point(keys, 2.0 * pull * (1 + 1e-9), p=np.inf)])
        order = np.lexsort((np.arange(len(faces)), -near))                 # densest first, then by index
        c = ring_classes(X[order], pull)
        label = np.empty(len(faces), dtype=np.int64)
        hand, shift = np.empty_like(label), np.empty_like(label)
        label[order], hand[order], shift[order] = c.label, c.hand, c.shift
        size = np.bincount(label, minlength=c.count)
        keep = size[label] >= 2
        j = np.arange(k)[None, :] + shift[:, None]
        idx = np.where(hand[:, None] == 0, j % k, (-j) % k)              # leader corner j -> own corner
        corners = mesh.F[faces[:, None], idx]
        _, lab = np.unique(label[keep], return_inverse=True)
        out.append((corners[keep], lab.ravel() + base))
        base += int(lab.max()) + 1 if len(lab) else 0
    return out


def _limit_rows(x: np.ndarray, L, ref, cap: float) -> tuple[np.ndarray, sp.csr_matrix]:
    """Hinge rows ``max(0, |v - y| - cap)`` of every vertex (``y`` its closest point on ``ref``) and
    their Jacobian ``(n, L.size)``: zero while a vertex is within ``cap`` of the reference."""
    V = L.view(x, "vertices")
    Y, _ = ref.closest(V)
    D = V - Y
    d = np.linalg.norm(D, axis=1)
    over = np.nonzero(d > cap)[0]
    r = np.where(d > cap, d - cap, 0.0)
    U = D[over] / np.maximum(d[over], 1e-300)[:, None]
    cols = L.index("vertices")[over].ravel()
    J = sp.csr_matrix((U.ravel(), (np.repeat(over, 3), cols)), shape=(len(V), L.size))
    return r, J


def _symmetry_rows(x: np.ndarray, L, group) -> list[tuple[np.ndarray, sp.csr_matrix]]:
    """Rows ``V[P_g] - (V R_g^T + t_g)`` (``3 n`` each) of every symmetry ``g`` of ``group`` but the
    identity, and their Jacobians: the pull keeps the design's symmetry (the closeness term alone
    would not, :mod:`optimize.mesh.symmetry`)."""
    V = L.view(x, "vertices")
    n = len(V)
    idx = L.index("vertices")
    out = []
    for g in group.maps[1:]:
        r = (V[g.perm] - (V @ g.R.T + g.t)).ravel()
        rows = np.arange(3 * n)
        A = sp.csr_matrix((np.ones(3 * n), (rows, idx[g.perm].ravel())), shape=(3 * n, L.size))
        B = sp.kron(sp.identity(n), sp.csr_matrix(g.R), format="csr")              # row i: R v_i
        B = sp.csr_matrix((B.data, idx.ravel()[B.indices], B.indptr), shape=(3 * n, L.size))
        out.append((r, (A - B).tocsr()))
    return out


def _targets(V: np.ndarray, corners: np.ndarray, label: np.ndarray) -> np.ndarray:
    """(q, P): each face's class mean of the aligned corner distances at ``V``."""
    D = congruence.distances(V, corners)
    count = np.bincount(label)
    mean = np.zeros((len(count), D.shape[1]))
    np.add.at(mean, label, D)
    return (mean / count[:, None])[label]


def rationalize(form, run: guided.RunState, x_in: np.ndarray, *, ref, glide, convex, tol, fairness: float,
                closeness: float, pull: float, scale: float, limit: float, tol_mm: float = TOLERANCE_MM,
                group=None, callback=None) -> tuple[guided.RunState, dict]:
    """Pull near-congruent faces into classes from a converged ``run`` (normalized coordinates,
    ``x = (V - centre) / scale``; ``pull``, ``limit`` and ``tol_mm`` in model units).  Returns the
    run with the accepted rounds (history entries ``"phase": "rationalize"``) and a JSON-ready
    record: the different faces within ``tol_mm`` before and after (mirror images as one, and
    apart), the rounds, the largest distance to the reference before and after, the roughness
    before and after, the seconds.  group : the design's symmetries
    (:class:`optimize.mesh.symmetry.Group`, normalized coordinates) the pull keeps, or None."""
    t0 = time.perf_counter()
    L, mesh = form.layout, form.mesh

    def facts(x):
        V = L.view(x, "vertices")
        c: Classes = face_classes(mesh, V * scale, tol_mm)
        dist = float(ref.distance(V).max()) * scale if ref is not None else 0.0
        return {"faces": mesh.n_faces, "shapes": c.count, "with_hands": c.positions, "most_of_one_shape": c.largest,
                "max_distance": dist, "roughness": roughness(mesh, V)}

    before = facts(run.x)
    best, best_facts, rounds, stop = run, before, 0, "no class left to pull"
    if run.status != "converged":
        stop = f"the solve ended {run.status}: nothing to rationalize"
    cap = max(limit, before["max_distance"])
    weight, spread = WEIGHT, np.inf
    while run.status == "converged" and rounds < ROUNDS:
        V = L.view(best.x, "vertices")
        groups = [(c, lab) for c, lab in pull_classes(mesh, V * scale, pull) if len(c)]
        if not groups:
            break
        targets = [_targets(V, c, lab) for c, lab in groups]
        w = np.sqrt(weight)

        def extra(x, groups=groups, targets=targets, w=w):
            rows = [congruence.terms(x, L, c, t) for (c, _), t in zip(groups, targets)]
            if ref is not None:
                rows.append(_limit_rows(x, L, ref, MARGIN * cap / scale))
            if group is not None:
                rows.extend(_symmetry_rows(x, L, group))
            return w * np.concatenate([r for r, _ in rows]), w * sp.vstack([J for _, J in rows], format="csr")

        trial = fairing.refine(form, best, x_in, ref=ref, glide=glide, convex=convex, tol=tol, fairness=fairness,
                               closeness=closeness, max_iter=ITERATIONS, callback=callback, extra=extra,
                               phase="rationalize")
        if trial.nit == best.nit:
            stop = trial.message[len(best.message):].lstrip("; ") or "no step kept"
            break
        rounds += 1
        got = facts(trial.x)
        Vt = L.view(trial.x, "vertices")
        new_spread = max(float(np.abs(congruence.distances(Vt, c) - _targets(Vt, c, lab)).max()) for c, lab in groups)
        log.info("rationalize round %d: %d -> %d shapes, distance %.3g (limit %.3g), spread %.3g", rounds,
                 best_facts["shapes"], got["shapes"], got["max_distance"], cap, new_spread * scale)
        if got["max_distance"] > cap:
            if weight > WEIGHT * 1e-3:  # closeness counts more: the same classes again, pulled less hard
                weight /= 10.0
                stop = f"round {rounds} moved the design beyond the limit: pulled less hard"
                continue
            stop = (f"round {rounds} moved the design {got['max_distance']:.4g} from its reference, beyond the "
                    f"limit {cap:.4g}: dropped")
            break
        fewer = got["shapes"] < best_facts["shapes"]
        closer = got["shapes"] == best_facts["shapes"] and new_spread < 0.5 * spread
        if not (fewer or closer):
            stop = f"round {rounds} made no fewer shapes ({got['shapes']})"
            break
        best, best_facts, spread = trial, got, new_spread
        stop = f"{rounds} round(s)"
    record = {"pull": pull, "tolerance": tol_mm, "limit": cap, "rounds": rounds, "stop": stop,
              "before": before, "after": best_facts, "seconds": time.perf_counter() - t0}
    if best is not run:
        best.message = (f"{run.message}; rationalized: {before['shapes']} -> {best_facts['shapes']} shapes of "
                        f"{mesh.n_faces} faces within {tol_mm:g} ({stop})")
    return best, record
