"""Subdivision with perturbation: the modelling loop of the paper (Fig. 7, 8, 9, 14, 16).

A designer draws a coarse control mesh; each round subdivides the current
mesh once and perturbs the result to the target (PQ, conical, circular, or a
developable strip), the unperturbed subdivided mesh serving as the reference
surface that closeness pulls towards.  Every level's mesh, optimizer result
and measures are kept.

Schemes: ``"catmull_clark"``, ``"doo_sabin"`` (any polygon mesh) and
``"chaikin"``, ``"lane_riesenfeld"`` (strip meshes: both boundary polylines
refined, :func:`optimize.modelling.strips.refine_strips`).  Target ``"strip"`` is the
paper's developable-strip target (``optimize.solvers.paper``); a mesh made of several
strips is optimized strip by strip.  Target ``"none"`` subdivides only.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..api import optimize_mesh as _optimize_mesh  # the default optimizer (this package sits above the api)
from ..errors import ConfigError
from ..mesh import Mesh, measures
from ..tolerances import DEFAULT, Tolerances
from .subdivision import SCHEMES, subdivide

log = logging.getLogger(__name__)

__all__ = ["LevelResult", "HierarchyResult", "subdivide_and_perturb", "refine_strip", "ALL_SCHEMES"]

ALL_SCHEMES = tuple(SCHEMES)
STRIP_METHOD = "penalty"
"""The paper's method used for target "strip" when ``method="default"`` is asked for
(the default solver has no strip target; the paper reports penalty and SQP on its strips)."""
TARGETS = ("pq", "conical", "circular", "strip", "none")


@dataclass
class LevelResult:
    """One round of the hierarchy.

    level : int, 1 for the first subdivision (0: the control mesh perturbed).
    mesh : Mesh, the perturbed mesh of this level (the reference when target is "none").
    reference : Mesh, the unperturbed subdivided mesh (closeness reference).
    S : (n_level, n_previous) scipy CSR, ``reference.V == S @ previous.V``.
    result : OptimizeResult or None (target "none").
    measures : dict, ``measures.summary`` of ``mesh`` (+ ``"strips"`` for strip meshes).
    seconds : dict, ``subdivide`` and ``optimize`` wall times.
    """

    level: int
    mesh: Mesh
    reference: Mesh
    S: sp.csr_matrix
    result: object | None
    measures: dict
    seconds: dict = field(default_factory=dict)

    @property
    def success(self) -> bool:
        return self.result is None or bool(self.result.success)

    def as_dict(self) -> dict:
        """JSON-ready facts of the level."""
        r = self.result
        return {"level": self.level, "vertices": self.mesh.n_vertices, "faces": self.mesh.n_faces,
                "status": None if r is None else r.status, "success": self.success,
                "nit": 0 if r is None else r.nit, "message": "" if r is None else r.message,
                "max_distance": None if r is None else r.max_distance,
                "final_energy": r.history[-1].get("energy") if r is not None and r.history else None,
                "seconds": self.seconds, "measures": self.measures}


@dataclass
class HierarchyResult:
    """All levels of :func:`subdivide_and_perturb` (``levels[-1].mesh`` is the final mesh)."""

    control: Mesh
    scheme: str
    target: str
    levels: list = field(default_factory=list)

    @property
    def mesh(self) -> Mesh:
        return self.levels[-1].mesh if self.levels else self.control

    @property
    def success(self) -> bool:
        """True when every level met its tolerances."""
        return all(lv.success for lv in self.levels)

    def as_dict(self) -> dict:
        return {"control": {"name": self.control.name, "vertices": self.control.n_vertices,
                            "faces": self.control.n_faces},
                "scheme": self.scheme, "target": self.target, "success": self.success,
                "levels": [lv.as_dict() for lv in self.levels]}


def subdivide_and_perturb(control: Mesh, levels: int, *, scheme: str = "catmull_clark",
                          target: str = "conical", perturb_control: bool = False,
                          surface: Mesh | None = None, optimizer=None, **optimize_kwargs) -> HierarchyResult:
    """``levels`` rounds of "subdivide once, then perturb to ``target``".

    Parameters
    ----------
    control : Mesh
        The coarse mesh (never modified).
    levels : int >= 0
        Rounds.  ``levels = 0`` perturbs the control mesh only.
    scheme : one of :data:`ALL_SCHEMES`.
    target : ``"pq"`` | ``"conical"`` | ``"circular"`` | ``"strip"`` | ``"none"``.
    perturb_control : also perturb the control mesh first (level 0).
    surface : the surface the control mesh was made from (a remeshed triangle
        surface): the reference of level 0 (closeness, gliding boundary)
        instead of the control mesh itself.
    optimizer : the callable run at every level, with the signature of
        :func:`optimize.api.optimize_mesh` (None: that function).
    **optimize_kwargs
        Passed to the optimizer at every level (``method``,
        ``fixed``, ``fairness``, ``closeness``, ``tol``, ``max_iter``,
        ``callback``...); ``reference`` is set per level.  ``fixed`` as an
        index array refers to control vertices and is kept through
        Catmull-Clark levels (coarse vertex ``i`` stays fine vertex ``i``); ``rationalize``
        goes to the last level only (the panels that are built);
        other schemes renumber, so they accept only ``"boundary"``/``"corners"``.
        For target ``"strip"`` the method ``"default"`` means
        :data:`STRIP_METHOD` (the paper's penalty method).

    Returns :class:`HierarchyResult`; levels that miss their tolerance are kept
    and marked (``success`` False), the next level starts from them.
    """
    if isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or levels < 0:
        raise ConfigError(f"levels: {levels!r}, expected an integer >= 0")
    if scheme not in ALL_SCHEMES:
        raise ConfigError(f"scheme: {scheme!r} is not known, expected one of {ALL_SCHEMES}")
    if target not in TARGETS:
        raise ConfigError(f"target: {target!r} is not known, expected one of {TARGETS}")
    if "reference" in optimize_kwargs:
        raise ConfigError("reference: set by subdivide_and_perturb (each level's unperturbed "
                          "subdivision), expected not to be given")
    fixed = optimize_kwargs.get("fixed")
    if fixed is not None and not isinstance(fixed, str) and scheme != "catmull_clark" and levels:
        raise ConfigError(f"fixed: vertex indices cannot follow scheme {scheme!r} (it renumbers "
                          "vertices), expected 'boundary', 'corners' or None, or scheme catmull_clark")
    tol = optimize_kwargs.get("tol", DEFAULT)
    out = HierarchyResult(control, scheme, target)
    mesh = control
    early = {k: v for k, v in optimize_kwargs.items() if k != "rationalize"}  # only the last level is the roof
    if perturb_control or levels == 0:
        out.levels.append(_perturb(0, control, sp.identity(control.n_vertices, format="csr"),
                                   scheme, target, tol, 0.0, optimize_kwargs if levels == 0 else early,
                                   surface, optimizer))
        mesh = out.levels[-1].mesh
    for level in range(1, levels + 1):
        t0 = time.perf_counter()
        ref, S = subdivide(mesh, scheme, 1)
        ref.name = f"{control.name}-L{level}"
        lv = _perturb(level, ref, S, scheme, target, tol, time.perf_counter() - t0,
                      optimize_kwargs if level == levels else early, optimizer=optimizer)
        out.levels.append(lv)
        mesh = lv.mesh
        log.info("level %d (%s, %s): %d vertices, %s", level, scheme, target, ref.n_vertices,
                 "no optimization" if lv.result is None else lv.result.message)
    return out


def refine_strip(strip: Mesh, levels: int, *, scheme: str = "chaikin", target: str = "strip",
                 **optimize_kwargs) -> HierarchyResult:
    """Strip refinement (paper Fig. 8, 9, 16): ``levels`` rounds of refining both boundary
    polylines by ``scheme`` (``"chaikin"`` | ``"lane_riesenfeld"``) and perturbing to ``target``."""
    if scheme not in ("chaikin", "lane_riesenfeld"):
        raise ConfigError(f"scheme: {scheme!r} does not refine strips, expected 'chaikin' or "
                          "'lane_riesenfeld'")
    return subdivide_and_perturb(strip, levels, scheme=scheme, target=target, **optimize_kwargs)


def _perturb(level: int, ref: Mesh, S, scheme: str, target: str, tol: Tolerances, t_sub: float,
             kwargs: dict, surface: Mesh | None = None, optimizer=None) -> LevelResult:
    t0 = time.perf_counter()
    if target == "none":
        result, mesh = None, ref
    elif target == "strip" or scheme in ("chaikin", "lane_riesenfeld"):
        result = _optimize_strips(ref, target, kwargs, optimizer)
        mesh = result.mesh
    else:
        result = (optimizer or _optimize_mesh)(ref, target, reference=ref if surface is None else surface, **kwargs)
        mesh = result.mesh
    seconds = {"subdivide": t_sub, "optimize": time.perf_counter() - t0}
    return LevelResult(level, mesh, ref, S, result, _measures(mesh, tol, scheme, target), seconds)


def _measures(mesh: Mesh, tol: Tolerances, scheme: str, target: str) -> dict:
    out = measures.summary(mesh, tol)
    if target == "strip" or scheme in ("chaikin", "lane_riesenfeld"):
        from .strip_analysis import strip_report

        out["strips"] = strip_report(mesh, tol=tol.strip_parallel)
    return out


def _optimize_strips(mesh: Mesh, target: str, kwargs: dict, optimizer=None):
    """Optimize every strip of ``mesh`` on its own; one merged OptimizeResult."""
    from .strips import strip_layouts

    optimize_mesh = optimizer or _optimize_mesh
    kw = dict(kwargs)
    if target == "strip" and kw.get("method", "default") == "default":
        kw["method"] = STRIP_METHOD
    layouts = strip_layouts(mesh)
    if len(layouts) == 1:
        return optimize_mesh(mesh, target, reference=mesh, **kw)
    results, blocks = [], []
    for k, lay in enumerate(layouts):  # one solve per strip
        idx = np.unique(mesh.F[lay.faces])
        local = np.full(mesh.n_vertices, -1, dtype=np.int64)
        local[idx] = np.arange(len(idx))
        sub = Mesh(mesh.V[idx], local[mesh.F[lay.faces]], name=f"{mesh.name}-strip{k}")
        results.append(optimize_mesh(sub, target, reference=sub, **kw))
        blocks.append(idx)
    return _merge(mesh, results, blocks, target, kw.get("tol", DEFAULT))


def _merge(mesh: Mesh, results: list, blocks: list, target: str, tol: Tolerances):
    """One OptimizeResult for a mesh whose components were optimized separately."""
    from ..result import STATUSES, OptimizeResult

    V = mesh.V.copy()
    for r, idx in zip(results, blocks):
        V[idx] = r.mesh.V
    out = mesh.with_vertices(V)
    status = max((r.status for r in results), key=STATUSES.index)  # the worst one
    timings: dict = {}
    for r in results:
        for key, val in r.timings.items():
            timings[key] = timings.get(key, 0.0) + float(val)
    msg = "; ".join(f"strip {k}: {r.message}" for k, r in enumerate(results))
    return OptimizeResult(mesh=out, success=all(r.success for r in results), status=status,
                          message=msg, nit=max(r.nit for r in results),
                          history=[{"strip": k, **h} for k, r in enumerate(results) for h in r.history],
                          defects=measures.summary(out, tol),
                          max_distance=max(r.max_distance for r in results),
                          timings=timings, method=results[0].method, target=target)

