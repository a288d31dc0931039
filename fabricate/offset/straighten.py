"""Use the free directions of under-determined node axes to make the beams planar.

A boundary vertex with two faces (or one), and an interior vertex whose face
normals span only a plane (a cylinder-like vertex), has offset vectors
``X_v + B_v p_v`` that all keep every face at exactly the offset distance
(``n_i . B_v = 0``, see :mod:`fabricate.offset.axes`).  The beam on an edge
``(v, w)`` is planar when the two node axes and the edge are coplanar:

    r_e = e_hat . (X_v x X_w) = 0,      e_hat = (w - v) / |w - v|.

Gauss-Newton with a small Levenberg-Marquardt damping on the free parameters
``p`` drives ``r`` to zero on every edge that touches a free vertex, starting
from the minimum-norm axes (``p = 0``), so the result is the nearest solution.
It stops when the largest residual is below ``tol``.  When the residual
cannot reach zero near the start (a closed boundary loop of a mesh without
symmetry has, in general, no nearby solution: the axes would run off towards
the tangent plane), a least-squares compromise ``|r|^2 + lam^2 |p|^2`` is used
and the remaining twist is reported.
"""
from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

from .axes import AxisFit

log = logging.getLogger(__name__)

MAX_TURN_DEG = 30.0
"""A turned axis may leave the bisector (minimum-norm) axis by at most this angle."""

LAMBDAS = (0.0, 1e-4, 1e-3, 1e-2, 1e-1)
"""Weights of ``|p|^2`` tried in turn: exact planarity first (accepted only when it
converges), then least-squares compromises that keep the axes closer to the bisectors."""


def coplanarity_residual(V: np.ndarray, X: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """(e,) float: ``e_hat . (X_v x X_w)`` for ``edges (e, 2)``, ``V, X (n, 3)``."""
    d = V[edges[:, 1]] - V[edges[:, 0]]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return np.einsum("ej,ej->e", d, np.cross(X[edges[:, 0]], X[edges[:, 1]]))


def straighten_free_axes(V: np.ndarray, edges: np.ndarray, fit: AxisFit, *,
                         tol: float = 1e-13, max_iter: int = 50) -> tuple[AxisFit, dict]:
    """Turn the free node axes so that the beams on their edges are planar.

    Parameters
    ----------
    V : (n, 3) float, vertex positions
    edges : (e, 2) int, all mesh edges
    fit : AxisFit from :func:`fabricate.offset.axes.fit_axes`
    tol : stop when ``max |r_e| <= tol`` (``r_e`` is a sine-like number)

    Returns
    -------
    (AxisFit, info) : the new fit and a JSON-ready ``info`` dict (free
    vertices, residual before/after, iterations, status, the regularization
    used).  When no exact solution is found, least-squares compromises with
    growing weight on ``|p|`` are tried; a result that turns an axis more than
    ``MAX_TURN_DEG`` from its bisector or does not lower the residual is
    refused and the fit is returned unchanged (status "refused").
    """
    rank = fit.free_rank
    free_v = np.nonzero(rank > 0)[0]
    info = {"free_vertices": int(free_v.size), "edges": 0, "iterations": 0,
            "residual_before": 0.0, "residual_after": 0.0, "status": "nothing free"}
    if free_v.size == 0:
        return fit, info
    prob = FreeAxes(V, edges, fit)
    E = prob.E
    X0 = fit.offset
    r0 = coplanarity_residual(V, X0, E)
    info.update(edges=int(len(E)), residual_before=float(np.abs(r0).max(initial=0.0)))
    if info["residual_before"] <= tol:
        info.update(status="already planar", residual_after=info["residual_before"])
        return fit, info
    reasons = []
    for lam in LAMBDAS:  # exact first; a least-squares compromise when there is no nearby solution
        p, it, status = _gauss_newton(prob, lam, tol, max_iter)
        X = prob.offsets(p)
        cos_theta = 1.0 / np.linalg.norm(X, axis=1)
        r = coplanarity_residual(V, X, E)
        turn = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", X * cos_theta[:, None], fit.axes), -1, 1)))
        if lam == 0.0 and status != "converged":
            reasons.append(f"exact: {status} at residual {np.abs(r).max():.3g}")
        elif turn.max() > MAX_TURN_DEG:
            reasons.append(f"lambda {lam:g}: vertex {int(np.argmax(turn))} would turn {turn.max():.1f} deg")
        elif np.abs(r).max(initial=0.0) >= info["residual_before"]:
            reasons.append(f"lambda {lam:g}: no improvement")
        else:
            break
    else:
        info.update(status="refused", residual_after=info["residual_before"], reason="; ".join(reasons))
        log.info("planar-beam axes refused: %s", info["reason"])
        return fit, info
    info.update(iterations=it, residual_after=float(np.abs(r).max(initial=0.0)), status=status,
                regularization=lam, max_turn_deg=float(turn.max()))
    if reasons:
        info["tried"] = reasons
    log.debug("straightened %d free axes: residual %.3g -> %.3g in %d iterations (%s, lambda %g)",
              free_v.size, info["residual_before"], info["residual_after"], it, status, lam)
    return replace(fit, offset=X, axes=X * cos_theta[:, None], cos_theta=cos_theta), info


class FreeAxes:
    """The planar-beam problem on the free parameters ``p`` (one block of ``free_rank`` per vertex).

    V : (n, 3) positions; edges : (e, 2); fit : AxisFit.  ``E (k, 2)`` are the
    edges touching a free vertex, ``start (n + 1,)`` the offset of each vertex's
    block in ``p``, ``n_par`` its length.
    """

    def __init__(self, V: np.ndarray, edges: np.ndarray, fit: AxisFit):
        self.V, self.X0, self.B, self.rank = V, fit.offset, fit.free_basis, fit.free_rank
        self.E = edges[(self.rank[edges[:, 0]] > 0) | (self.rank[edges[:, 1]] > 0)]
        self.start = np.concatenate([[0], np.cumsum(self.rank)]).astype(np.int64)
        self.n_par = int(self.start[-1])

    def offsets(self, p: np.ndarray) -> np.ndarray:
        """(n, 3) offset vectors ``X0 + B p``."""
        slot = np.arange(2)[None, :] < self.rank[:, None]  # (n, 2)
        idx = np.where(slot, self.start[:-1, None] + np.arange(2)[None, :], 0)
        coef = np.where(slot, p[idx] if self.n_par else 0.0, 0.0)
        return self.X0 + np.einsum("njk,nk->nj", self.B, coef)

    def residual(self, p: np.ndarray) -> np.ndarray:
        """(k,) coplanarity residuals of the edges ``E``."""
        return coplanarity_residual(self.V, self.offsets(p), self.E)

    def jacobian(self, p: np.ndarray) -> sp.csr_matrix:
        """(k, n_par) sparse derivative of :meth:`residual` (exact: ``r`` is bilinear)."""
        V, E, X, B, rank = self.V, self.E, self.offsets(p), self.B, self.rank
        d = V[E[:, 1]] - V[E[:, 0]]
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        rows, cols, vals = [], [], []
        for end, g in ((0, np.cross(X[E[:, 1]], d)), (1, np.cross(d, X[E[:, 0]]))):
            v = E[:, end]
            for k in range(2):  # two possible free directions per vertex
                sel = rank[v] > k
                rows.append(np.nonzero(sel)[0])
                cols.append(self.start[v[sel]] + k)
                vals.append(np.einsum("ej,ej->e", g[sel], B[v[sel], :, k]))
        return sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(len(E), self.n_par)).tocsr()


def _gauss_newton(prob: FreeAxes, lam: float, tol: float, max_iter: int):
    """Minimize ``|r(p)|^2 + lam^2 |p|^2`` from ``p = 0``; returns ``(p, iterations, status)``.

    ``lam = 0``: "converged" when ``max |r| <= tol``.  ``lam > 0``: "converged"
    when the step is below ``1e-12`` (a stationary point of the compromise).
    "stalled" when no step decreases the objective (or, for ``lam = 0``, the
    step vanishes first); ``max_iter`` is a safety net reported as such.
    """
    p = np.zeros(prob.n_par)
    r = prob.residual(p)
    cost = float(r @ r)
    eye = sp.identity(prob.n_par, format="csc")
    for it in range(max_iter):
        if lam == 0.0 and np.abs(r).max(initial=0.0) <= tol:
            return p, it, "converged"
        J = prob.jacobian(p)
        H = (J.T @ J).tocsc()
        mu = 1e-10 * max(float(H.diagonal().max(initial=0.0)), 1e-300)
        step = np.atleast_1d(spsolve(H + (mu + lam ** 2) * eye, -(J.T @ r) - lam ** 2 * p))
        if np.abs(step).max(initial=0.0) <= 1e-12 * (1.0 + np.abs(p).max(initial=0.0)):
            return p, it, "converged" if lam > 0 else "stalled"
        for _ in range(12):  # backtrack: halve the step until the objective decreases
            p_new = p + step
            r_new = prob.residual(p_new)
            cost_new = float(r_new @ r_new) + lam ** 2 * float(p_new @ p_new)
            if cost_new < cost:
                break
            step = 0.5 * step
        else:
            return p, it, "stalled"
        p, r, cost = p_new, r_new, cost_new
    return p, max_iter, "max_iter"
