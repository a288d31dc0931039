"""The constraint set of each target, as the paper writes it (section 2.2 and section 3).

=========  ==========================================================  ==========================
target     constraint rows (each ``(r, J)``, radians or dimensionless)  tested tolerances
=========  ==========================================================  ==========================
pq         angle sum per face (k >= 4)                                 planarity
conical    angle sum per face + angle balance per valence-4 vertex     planarity, conical
circular   opposite-angle pairs per quad (+ angle sum on n-gons, n>4)  planarity, circular
strip      angle sum + four determinants per quad (weight ``mu = 1``)  planarity, det
=========  ==========================================================  ==========================

The angle rows are the terms' (:mod:`optimize.terms`): the angle sum
:mod:`~optimize.terms.facesum`, the balance :mod:`~optimize.terms.anglebalance`,
the opposite-angle pairs :mod:`~optimize.terms.anglesum` (the default method's
corner sets; the paper's methods evaluate them on fixed patterns,
:mod:`optimize.solvers.paper.system`); the determinants are the paper's own
(:mod:`optimize.terms.determinants`).  ``strip`` requires a single row of quads:
open, closed, or closed with a half twist (a Moebius band).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ...errors import ConfigError, MeshError
from ...mesh import Mesh
from ...terms import anglebalance, anglesum, facesum

TARGETS = ("pq", "conical", "circular", "strip")


@dataclass(frozen=True)
class Term:
    """One block of constraint rows.

    name : str, key in histories and multiplier slices.
    kind : "angle" (signed sums of corner angles: row ``i`` is
        ``sum_s signs[s] phi[corners[i, s]] - offset[i]`` over the slots ``corners >= 0``,
        the corner sets of the terms :mod:`optimize.terms.facesum`,
        :mod:`~optimize.terms.anglebalance` and :mod:`~optimize.terms.anglesum`), "det"
        (the four strip determinants of every quad) or "det1" (their alternating mean,
        one row per quad: :func:`optimize.terms.determinants.det_combined_local`).
    weight : float, the block's weight in the penalty energy (``mu`` for ``det``).
    """

    name: str
    kind: str
    weight: float = 1.0
    corners: np.ndarray | None = None
    signs: np.ndarray | float = 1.0
    offset: np.ndarray | None = None

    def signs_matrix(self, n_corners: int) -> sp.csr_matrix:
        """(r, c) sparse ``S``: the rows as combinations of corner angles, ``r = S @ phi - offset``
        (angle terms only)."""
        corners = np.asarray(self.corners)
        signs = np.broadcast_to(np.asarray(self.signs, dtype=float), corners.shape)
        mask = corners >= 0
        return sp.csr_matrix((signs[mask], (np.nonzero(mask)[0], corners[mask])),
                             shape=(corners.shape[0], n_corners))


def check_strip(mesh: Mesh) -> None:
    """Raise :class:`MeshError` unless ``mesh`` is one connected row of quads.

    Every face must be a quad sharing at most two edges, opposite ones, with
    other faces, and every vertex must lie on the boundary.
    """
    t = mesh.topology
    if not mesh.is_quad:
        raise MeshError(f"{mesh.name}: target 'strip' needs quads only, found face sizes "
                        f"{sorted(set(mesh.face_sizes.tolist()))}")
    if t.n_components != 1:
        raise MeshError(f"{mesh.name}: target 'strip' needs one connected row of quads, "
                        f"found {t.n_components} components")
    inner = ~t.is_boundary_edge[t.corner_edge].reshape(-1, 4)  # (m, 4): slot j shared
    count = inner.sum(axis=1)
    opposite = (inner[:, 0] & inner[:, 2]) | (inner[:, 1] & inner[:, 3])
    bad = (count > 2) | ((count == 2) & ~opposite)
    if bad.any():
        f = int(np.argmax(bad))
        raise MeshError(f"{mesh.name}: target 'strip' needs a single row of quads; face {f} shares "
                        f"{int(count[f])} edges with other faces, expected at most two opposite ones")
    if not t.is_boundary_vertex.all():
        v = int(np.argmin(t.is_boundary_vertex))
        raise MeshError(f"{mesh.name}: target 'strip' needs a single row of quads; vertex {v} is "
                        "interior, expected every vertex on the boundary")


def target_terms(mesh: Mesh, target: str, mu: float | None = None) -> list[Term]:
    """The constraint blocks of ``target`` for ``mesh``.

    mu : weight of the determinant terms in the penalty energy; default 1 for
        ``strip`` and 0 (not used) otherwise, as in the paper.  ``mu > 0`` on a
        quad mesh that is not a strip adds the determinant rows too.
    Raises :class:`ConfigError` for an unknown target.
    """
    if target not in TARGETS:
        raise ConfigError(f"target {target!r} is not known to the paper's methods, expected one of {TARGETS}")
    if target == "strip":
        check_strip(mesh)
    mu = (1.0 if target == "strip" else 0.0) if mu is None else float(mu)
    sizes = mesh.face_sizes
    if target == "circular":
        terms = [Term("circular", "angle", 1.0, *anglesum.rows(mesh))]
        big = np.nonzero(sizes > 4)[0]
        if big.size:
            terms.append(Term("angle_sum", "angle", 1.0, *facesum.rows(mesh, big)))
    else:
        terms = [Term("angle_sum", "angle", 1.0, *facesum.rows(mesh))]
    if target == "conical":
        terms.append(Term("balance", "angle", 1.0, *anglebalance.rows(mesh)))
    if mu > 0:
        if not np.any(sizes == 4):
            raise ConfigError(f"mu = {mu}: determinant terms need quads, {mesh.name} has none")
        terms.append(Term("det", "det", weight=mu))
    return terms


def sqp_terms(mesh: Mesh, terms: list[Term]) -> list[Term]:
    """The rows SQP imposes as equality constraints.

    With determinant rows present, planarity of the quads is expressed by one
    row per quad, the alternating mean of the four determinants ("det1"),
    and the quads' angle sums are left out.  The determinant's gradient does
    not vanish at a planar quad, the angle sum's does; a row whose gradient
    vanishes at the solution (or four rows of rank one) leaves the KKT
    conditions without (unique) multipliers, and SQP's multipliers then grow
    without bound.  For the same reason only the first circular row of each
    quad (``phi1 + phi3 = pi``) is kept: at a planar quad the two rows add up
    to the angle sum, so their gradients are opposite; with planarity and
    convexity the first implies the second.  Angle sums of n-gons (n > 4) and
    the conical balance stay.
    """
    if not any(t.kind == "det" for t in terms):
        return list(terms)
    out = []
    big = np.nonzero(mesh.face_sizes > 4)[0]
    for t in terms:
        if t.kind == "det":
            out.append(Term("det", "det1", t.weight))
        elif t.name == "circular":
            out.append(Term("circular", "angle", t.weight, t.corners[0::2], t.signs, t.offset[0::2]))
        elif t.name != "angle_sum":
            out.append(t)
        elif big.size:
            out.append(Term("angle_sum", "angle", t.weight, *facesum.rows(mesh, big)))
    return out


def default_mu(mesh: Mesh, target: str, method: str) -> float:
    """The determinant weight a method uses when none is given.

    The paper: ``mu = 1`` for strips, 0 otherwise, for the penalty method.
    SQP and hybrid add the determinant rows on every quad mesh (``mu = 1``):
    the angle rows are degenerate at planar faces (their gradients vanish),
    so a linearized constraint cannot see planarity and a Newton-KKT step
    cannot converge to a planar mesh from them alone (measured: with
    ``mu = 0`` SQP stalls at planarity 1e-4 .. 1e-3 on a perturbed surface
    of revolution).
    """
    if target == "strip":
        return 1.0
    return 1.0 if method in ("sqp", "hybrid") and np.any(mesh.face_sizes == 4) else 0.0


def tested_defects(target: str, mu: float | None = None) -> tuple[str, ...]:
    """Names of the measured defects that must reach tolerance for ``target``."""
    extra = {"pq": (), "conical": ("conical",), "circular": ("circular",), "strip": ("det",)}[target]
    if mu is not None and mu > 0 and "det" not in extra:
        extra = extra + ("det",)
    return ("planarity",) + extra
