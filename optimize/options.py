"""The optimizer's settings and their defaults, in one frozen object.

:class:`OptimizeOptions` is the one place the defaults live: ``optimize_mesh``,
the paper's solvers (``optimize.solvers.paper``) and the command line take their
defaults from :data:`DEFAULTS`, and a configuration schema can be derived from
:func:`dataclasses.fields` of it (names, types, defaults, the allowed values in
:data:`CHOICES`).  Constructing an instance checks every value and raises
:class:`optimize.errors.ConfigError` naming the key, the value and what was
expected.  This module imports only the standard library, the errors and the
tolerances (no NumPy, no solver), so a configuration layer may use it freely.
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field, fields, replace
from types import MappingProxyType
from typing import Any, Literal, Mapping

from .errors import ConfigError
from .fields import option
from .tolerances import Tolerances

TARGETS = ("pq", "conical", "circular", "strip")
"""What a mesh can be made: planar faces; PQ and conical; PQ and circular; a developable strip
(one row of quads; the paper's methods only)."""
DEFAULT_TARGETS = ("pq", "conical", "circular")
"""The targets of the default method."""
METHODS = ("default", "penalty", "sqp", "hybrid")
"""``default``: regularized Gauss-Newton on the quadratic formulation; the others: the paper's."""
PAPER_METHODS = METHODS[1:]
LINEAR_SOLVERS = ("auto", "pardiso", "superlu", "eliminate")
"""Sparse backends of the default method (``optimize.linalg.normal``): ``auto`` is PARDISO where
Intel MKL loads, else SuperLU."""
FORMULATIONS = ("auto", "auxiliary", "vertices")
PAPER_EXTRAS = ("mu", "kkt_tol", "kkt_patience", "hessian", "switch", "penalty_iter")
"""Settings only the paper's methods have (which method takes which: ``optimize.solvers.paper.run_paper_method``)."""
MAX_ITER_LIMIT = 100_000
"""Largest ``max_iter`` a run takes."""
MAX_ITER = 10_000
"""Largest ``max_iter`` of a configuration file (the upper bound of the field, a plausibility limit
like every upper bound of :func:`optimize.fields.option`; a run itself takes up to :data:`MAX_ITER_LIMIT`)."""
MAX_PULL = 1e4
"""Largest ``rationalize`` pull (model units: mm in ``fabricate``)."""
MAX_WEIGHT = 1e6
"""Largest fairness or closeness weight of a configuration file (the fields' upper bound)."""

CHOICES: Mapping[str, tuple] = MappingProxyType({
    "target": TARGETS, "method": METHODS, "linear_solver": LINEAR_SOLVERS, "formulation": FORMULATIONS,
    "torsion_free_beams": ("auto", True, False), "refine": ("auto", True, False),
})
"""The allowed values of the settings that take one of a few."""


@dataclass(frozen=True)
class OptimizeOptions:
    """Every setting of one optimizer run (the mesh, reference, fixed vertices and callback aside).

    Each field but ``tol`` and ``paper`` is an :func:`optimize.fields.option`: its default, the
    bounds of its config key and a one-line help (``fabricate``'s ``optimize`` section is derived
    from them).  The lower bounds of the weights are checked here too; ``max_iter`` takes
    0 .. :data:`MAX_ITER_LIMIT` here, 1 .. :data:`MAX_ITER` in a config file.

    target : one of :data:`TARGETS`.
    method : one of :data:`METHODS`.
    fairness, closeness : weights (>= 0, finite) of the scale-free fairness and tangent-plane
        closeness energies relative to the constraints (halved every iteration).
    max_iter : iteration budget (0 .. :data:`MAX_ITER_LIMIT`); a run never does more.
    tol : :class:`Tolerances`; the run converges when every defect of the target is within it.
    linear_solver : one of :data:`LINEAR_SOLVERS` (default method only).
    formulation : one of :data:`FORMULATIONS` (default method only).
    torsion_free_beams : ``"auto"``, True or False (default method, conical target).
    convex : keep every corner convex in the input convex (default method).
    refine : ``"auto"``, True or False (default method): the constrained fairing phase after a
        converged solve (:mod:`optimize.solvers.fairing`); ``"auto"`` runs it when the result lies
        further than ``tol.closeness`` from the reference.
    glide_boundary : free boundary vertices glide on the reference's boundary curve.
    rationalize : None (off) or the pull (model units, > 0): after a converged solve, faces within it
        of each other at every corner are pulled into exact classes of one shape with every
        constraint kept, within the closeness limit (``tol.closeness_mm``, else ``tol.closeness`` of
        the reference's diagonal): :mod:`optimize.solvers.rationalize` (default method).
    paper : extras of the paper's methods, names from :data:`PAPER_EXTRAS` (which method takes
        which is checked by ``optimize.solvers.paper.run_paper_method``); read-only mapping.
    """

    target: Literal[TARGETS] = option("pq", help="what the mesh is made (one of TARGETS)")
    method: Literal[METHODS] = option("default", help="default: regularized Gauss-Newton; penalty, sqp, "
                                      "hybrid: the paper's")
    fairness: float = option(1e-3, ge=0, le=MAX_WEIGHT, help="weight of the fairness energy (relative to "
                             "the constraints)")
    closeness: float = option(1e-2, ge=0, le=MAX_WEIGHT, help="weight of the closeness to the reference surface")
    max_iter: int = option(200, ge=1, le=MAX_ITER, help="iteration budget per level (the solver stops "
                           "earlier on its tests)")
    tol: Tolerances = field(default_factory=Tolerances)
    linear_solver: Literal[LINEAR_SOLVERS] = option("auto", help="sparse backend of the default method")
    formulation: Literal[FORMULATIONS] = option("auto", help="unknowns of the default method")
    torsion_free_beams: Literal["auto"] | bool = option("auto", help="conical: node axes solved with every "
                                                        "interior beam planar (auto: where needed)")
    convex: bool = option(True, help="default method: corners convex in the input stay convex")
    refine: Literal["auto"] | bool = option("auto", help="default method: after converging, minimize fairness "
                                            "(relative to the input) + closeness with every constraint exact "
                                            "(optimize.solvers.fairing); auto: when the result moved further than "
                                            "tolerances.closeness")
    glide_boundary: bool = option(False, help="free boundary vertices glide on the reference's boundary")
    rationalize: float | None = option(None, gt=0, le=MAX_PULL, help="default method: pull panels "
                                       "within this of each other at every corner into exact classes of one "
                                       "shape, every constraint kept (optimize.solvers.rationalize); null: off")
    paper: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        for key in ("target", "method", "linear_solver", "formulation", "torsion_free_beams", "refine"):
            val = getattr(self, key)
            if not any(val is c or (type(val) is type(c) and val == c) for c in CHOICES[key]):
                raise ConfigError(f"{key}: {val!r} is not known, expected one of {CHOICES[key]}")
        for key in ("fairness", "closeness"):
            val, low = getattr(self, key), _FIELDS[key].metadata["ge"]
            if isinstance(val, bool) or not isinstance(val, numbers.Real) or not (math.isfinite(val) and val >= low):
                raise ConfigError(f"{key}: weight {val!r}, expected a finite number >= {low:g}")
            object.__setattr__(self, key, float(val))
        mi = self.max_iter
        if isinstance(mi, bool) or not (isinstance(mi, numbers.Integral)
                                        or isinstance(mi, numbers.Real) and float(mi).is_integer()):
            raise ConfigError(f"max_iter: {mi!r}, expected a non-negative integer")
        if not 0 <= int(mi) <= MAX_ITER_LIMIT:
            raise ConfigError(f"max_iter: {mi!r}, expected a non-negative integer up to {MAX_ITER_LIMIT}")
        object.__setattr__(self, "max_iter", int(mi))
        if not isinstance(self.tol, Tolerances):
            raise ConfigError(f"tol: {self.tol!r}, expected a Tolerances object")
        for key in ("convex", "glide_boundary"):
            if not isinstance(getattr(self, key), bool):
                raise ConfigError(f"{key}: {getattr(self, key)!r}, expected true or false")
        pull = self.rationalize
        if pull is not None:
            if isinstance(pull, bool) or not isinstance(pull, numbers.Real) or not (math.isfinite(pull)
                                                                                   and 0 < pull <= MAX_PULL):
                raise ConfigError(f"rationalize: {pull!r}, expected null (off) or a pull in mm, > 0 and at most "
                                  f"{MAX_PULL:g}")
            object.__setattr__(self, "rationalize", float(pull))
        object.__setattr__(self, "paper", MappingProxyType(dict(self.paper)))
        if self.method == "default":
            if self.paper:
                raise ConfigError(f"options {sorted(self.paper)} are only for the paper's methods, "
                                  f"not {self.method!r}")
            if self.target == "strip":
                raise ConfigError("target: 'strip' is solved by the paper's methods only; use "
                                  "method='penalty', 'sqp' or 'hybrid'")
        elif self.rationalize is not None:
            raise ConfigError(f"rationalize: {self.rationalize:g} is a setting of the default method, not of "
                              f"{self.method!r}; leave it null")
        elif self.formulation != "auto" or self.linear_solver != "auto":
            raise ConfigError(f"formulation / linear_solver ({self.formulation!r}, {self.linear_solver!r}) "
                              f"are settings of the default method, not of {self.method!r}; leave them 'auto'")

    def replace(self, **changes) -> "OptimizeOptions":
        """A copy with some settings changed (checked again)."""
        return replace(self, **changes)

    def as_dict(self) -> dict[str, Any]:
        """The settings as plain values (``tol`` as its dict, ``paper`` as a dict)."""
        out = {f.name: getattr(self, f.name) for f in fields(self)}
        out["tol"], out["paper"] = self.tol.as_dict(), dict(self.paper)
        return out


_FIELDS = {f.name: f for f in fields(OptimizeOptions)}


DEFAULTS = OptimizeOptions()
"""The defaults (``optimize.options.DEFAULTS.fairness`` is the fairness weight a run uses when
none is given)."""
