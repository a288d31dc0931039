"""The paper's rows prepared for fixed patterns: one :class:`Term` per row block.

Which rows run is decided by the problem description
(:func:`optimize.terms.problem.describe`, the paper's section 2.2 and section 3):

=========  ==========================================================  ==========================
target     constraint rows (each ``(r, J)``, radians or dimensionless)  tested tolerances
=========  ==========================================================  ==========================
pq         angle sum per face (k >= 4)                                 planarity
conical    angle sum per face + angle balance per valence-4 vertex     planarity, conical
circular   opposite-angle pairs per quad (+ angle sum on n-gons, n>4)  planarity, circular
strip      angle sum + four determinants per quad (weight ``mu = 1``)  planarity, det
=========  ==========================================================  ==========================

Here each of the description's terms becomes a :class:`Term` (:func:`prepare`): the
corner sets of the angle terms (:mod:`optimize.terms.facesum`, the balance
:mod:`~optimize.terms.anglebalance`, the opposite-angle pairs
:mod:`~optimize.terms.anglesum`, the default method's corner sets), which the paper's
methods evaluate on fixed patterns (:mod:`optimize.solvers.paper.system`), or the
strip determinants (:mod:`optimize.terms.determinants`).  ``strip`` requires a single
row of quads: open, closed, or closed with a half twist (a Moebius band;
:func:`optimize.terms.problem.check_strip`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ...mesh import Mesh
from ...options import TARGETS
from ...terms import anglebalance, anglesum, facesum
from ...terms.problem import ProblemSpec, TermSpec, check_strip, describe

__all__ = ["TARGETS", "Term", "check_strip", "prepare", "prepare_all", "target_terms"]


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


def prepare(mesh: Mesh, spec: TermSpec, sets) -> Term:
    """The :class:`Term` (corner sets or determinants) of the description's term ``spec``
    (:class:`optimize.terms.problem.TermSpec`) on ``mesh``; ``sets`` the description's
    index sets (``ProblemSpec.sets``)."""
    if spec.module == "determinants":
        return Term(spec.name, "det1" if spec.options.get("form") == "mean" else "det", spec.weight)
    if spec.module == "facesum":
        faces = spec.options.get("faces")
        rows = facesum.rows(mesh) if faces is None else facesum.rows(mesh, sets[faces])
    elif spec.module == "anglebalance":
        rows = anglebalance.rows(mesh)
    elif spec.module == "anglesum":
        corners, signs, offset = anglesum.rows(mesh)
        if spec.options.get("rows") == "first":  # phi1 + phi3 = pi only (problem._paper_constraints)
            corners, offset = corners[0::2], offset[0::2]
        rows = (corners, signs, offset)
    else:
        raise ValueError(f"term {spec.name!r}: module {spec.module!r} has no rows for the paper's methods")
    return Term(spec.name, "angle", spec.weight, *rows)


def prepare_all(spec: ProblemSpec, kind: str) -> list[Term]:
    """The :class:`Term` of every row of ``kind`` in the description ``spec``, in order."""
    return [prepare(spec.mesh, t, spec.sets) for t in spec.rows(kind)]


def target_terms(mesh: Mesh, target: str, mu: float | None = None) -> list[Term]:
    """The penalty method's constraint blocks of ``target`` for ``mesh``
    (the description's least-squares rows, :func:`optimize.terms.problem.describe`).

    mu : weight of the determinant terms in the penalty energy; default 1 for
        ``strip`` and 0 (not used) otherwise, as in the paper.  ``mu > 0`` on a
        quad mesh that is not a strip adds the determinant rows too.
    Raises :class:`ConfigError` for an unknown target.
    """
    return prepare_all(describe(mesh, target, "penalty", mu=mu), "least_squares")
