"""The result of an optimization run (every method, every target).

Modelled on ``scipy.optimize.OptimizeResult``: the optimized mesh plus how the
run ended (``success``, ``status``, ``message``, ``nit``), the history of every
defect and energy per iteration, the final measured defects, the auxiliary
variables the later stages need (face normals; node axes and cone angles of a
conical mesh) and timings.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import ConvergenceError
from .mesh import Mesh, measures
from .tolerances import DEFAULT

STATUSES = ("converged", "folded", "degenerate", "stalled", "max_iter", "diverged")
TARGET_MEASURES = {"pq": ("planarity",), "conical": ("planarity", "conical"),
                   "circular": ("planarity", "circular"), "strip": ("planarity", "det")}
"""The measured defects (keys of ``OptimizeResult.defects``) each target must meet: a run is a
success only when every one is within its tolerance on the result as returned (in its own
coordinates, not the solver's scaled ones)."""
DEGENERATE = {"shrunk_edges": "with a shrunk edge", "straight_corners": "with a straight corner"}


@dataclass
class OptimizeResult:
    """What an optimizer returns.

    mesh : Mesh
        The optimized mesh: same faces and vertex order as the input.
    success : bool
        True exactly when every tolerance of the target was reached.
    status : str
        ``"converged"`` | ``"folded"`` (every tolerance reached, but faces that
        were convex became dented or flipped: ``defects["folded"]`` lists them) |
        ``"degenerate"`` (every tolerance reached, no fold, but faces with a shrunk
        edge or a straight corner: ``defects["shrunk_edges"]``,
        ``defects["straight_corners"]``) | ``"stalled"`` (no progress, or the solver's
        scaled iterate met the tolerances and the returned mesh does not) |
        ``"max_iter"`` | ``"diverged"`` (the last good iterate is returned).
    message : str
        One sentence saying why the run stopped, with the figures.
    nit : int
        Iterations done.
    history : list of dict
        One dict per iteration: ``planarity``, ``conical``, ``circular``
        (max defects), ``fairness``, ``closeness`` (energies), ``step``,
        ``residual`` and solver details.
    defects : dict
        Final measures of ``mesh`` (``measures.summary``), with ``folded``,
        ``shrunk_edges`` and ``straight_corners`` against the input (:func:`check_folds`).
    max_distance : float
        Max distance of a vertex to the reference surface / bbox diagonal of
        the reference.
    normals : (m, 3) float or None
        Unit face normals of the result.
    axes : (n, 3) float or None
        Unit node axes (conical target; rows of vertices where the cone is not
        defined hold the vertex normal estimate).
    cone_angles : (n,) float or None
        Cone half-angle ``theta_v`` (radians) between the axis and the face
        normals (conical target).
    multipliers : array or None
        Lagrange multipliers (SQP only).
    beam_axes : (n, 3) float or None
        Node axes solved together with planar beams (``torsion_free_beams``): the
        offset stage should use them (NaN rows, if any, are left to it).
    timings : dict
        Seconds per phase (``total``, ``solve``, ``assemble``, ``closest``...).
    method, target : str
    """

    mesh: Mesh
    success: bool
    status: str
    message: str
    nit: int
    history: list = field(default_factory=list)
    defects: dict = field(default_factory=dict)
    max_distance: float = 0.0
    normals: np.ndarray | None = None
    axes: np.ndarray | None = None
    cone_angles: np.ndarray | None = None
    multipliers: np.ndarray | None = None
    beam_axes: np.ndarray | None = None
    timings: dict = field(default_factory=dict)
    method: str = "default"
    target: str = "pq"

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ValueError(f"OptimizeResult.status is {self.status!r}, expected one of {STATUSES}")
        if self.success and self.status != "converged":
            raise ValueError(f"OptimizeResult: success=True with status {self.status!r}; "
                             "only a converged run is a success")

    def raise_for_status(self) -> "OptimizeResult":
        """Return ``self`` when the run succeeded; otherwise raise
        :class:`optimize.errors.ConvergenceError` (exit code 3) naming the status and every
        defect over its tolerance, for callers that want an exception rather than a status."""
        if self.success:
            return self
        facts = ", ".join(self.missed() + self.bad_faces()) or "no defect over tolerance"
        raise ConvergenceError(f"{self.mesh.name}: {self.method}/{self.target} ended {self.status} after "
                               f"{self.nit} iteration(s) ({facts}): {self.message}")

    def missed(self) -> list[str]:
        """``"planarity 6.4e-06 > 1e-06"`` for every measure of the target (:data:`TARGET_MEASURES`)
        over its tolerance in ``defects``: the one test of the tolerances a status, a message and
        a command's exit code are taken from."""
        out = []
        for key in TARGET_MEASURES.get(self.target, ("planarity",)):
            d = self.defects.get(key)
            if isinstance(d, dict) and d.get("ok") is False:
                out.append(f"{key} {d['max']:.3g} > {d['tolerance']:.3g}")
        return out

    def bad_faces(self) -> list[str]:
        """``"2 folded face(s)"``, ``"1 face(s) with a shrunk edge"``, ... for every non-zero count."""
        n = self.defects.get("folded", {}).get("count", 0)
        out = [f"{n} folded face(s)"] if n else []
        return out + [f"{self.defects[k]['count']} face(s) {what}" for k, what in DEGENERATE.items()
                      if self.defects.get(k, {}).get("count")]

    def report(self) -> dict:
        """A JSON-ready summary (no arrays): how the run ended, defects, timings, history."""
        return {
            "method": self.method, "target": self.target, "success": bool(self.success),
            "status": self.status, "message": self.message, "nit": int(self.nit),
            "max_distance": float(self.max_distance), "defects": self.defects,
            "timings": {k: float(v) for k, v in self.timings.items()},
            "history": [{k: _plain(v) for k, v in h.items()} for h in self.history],
        }

    def __repr__(self) -> str:
        return (f"OptimizeResult({self.method}/{self.target}: {self.status}, nit={self.nit}, "
                f"success={self.success}, max_distance={self.max_distance:.3g}, {self.mesh!r})")


def check_folds(result: OptimizeResult, V0: np.ndarray, advice: str = "",
                fold: float = DEFAULT.fold) -> OptimizeResult:
    """The one final check of every method, on the mesh as returned: record
    ``defects["folded"]`` (faces convex at ``V0 (n, 3)``, the input positions, that are dented,
    flipped or collapsed in ``result.mesh``: :func:`optimize.mesh.measures.folded_faces`) and the
    degenerate faces ``defects["shrunk_edges"]``, ``defects["straight_corners"]``
    (:func:`optimize.mesh.measures.degenerate`, against ``V0``); then a ``converged`` run
    becomes ``stalled`` when a measure of the target misses its tolerance on the returned mesh
    (:meth:`OptimizeResult.missed`: the solver measured its scaled iterate; far from the
    origin float64 may not hold what it reached), else ``folded`` with any fold, else
    ``degenerate`` with any degenerate face (none a success).  ``advice`` ends a fold's
    message; ``fold`` is ``Tolerances.fold``.
    Returns ``result`` (updated in place; calling it twice changes nothing more)."""
    mesh = result.mesh
    folded = np.nonzero(measures.folded_faces(mesh, mesh.V, V0, fold))[0]
    result.defects["folded"] = {"count": int(len(folded)), "faces": folded[:20].tolist()}
    result.defects.update(measures.degenerate(mesh, mesh.V, V0))
    if result.status != "converged":
        return result
    missed = result.missed()
    if missed:
        result.status, result.success = "stalled", False
        result.message = (f"the mesh as returned misses {', '.join(missed)}, though the solver's scaled iterate "
                          f"met the tolerances after {result.nit} iteration(s)" + _resolution_note(mesh, result))
    elif len(folded):
        result.status, result.success = "folded", False
        result.message = (f"{result.message}, but {len(folded)} face(s) that were convex became dented, "
                          f"flipped or collapsed (first: {folded[:5].tolist()})" + (f"; {advice}" if advice else ""))
    elif any(result.defects[k]["count"] for k in DEGENERATE):
        result.status, result.success = "degenerate", False
        d = result.defects
        result.message = (f"{result.message}, but {' and '.join(result.bad_faces())} (first: "
                          f"{sorted(set(d['shrunk_edges']['faces'][:5] + d['straight_corners']['faces'][:5]))[:5]}): "
                          f"a side below {measures.SHORT_EDGE:g} of its face's longest or {measures.SHRUNK:g} of its "
                          f"input length, or a corner whose sine is within {measures.STRAIGHT:g} of 0 (0 or 180 degrees); "
                          "such a quad is a triangle, no panel")
    return result


def _resolution_note(mesh: Mesh, result: OptimizeResult) -> str:
    """Why the returned mesh may miss what the scaled iterate met: its coordinates are too far
    from the origin for float64 to hold the tolerance (empty when they are not)."""
    rel = measures.relative_resolution(mesh)
    tol = min(result.defects[k]["tolerance"] for k in TARGET_MEASURES.get(result.target, ("planarity",))
              if isinstance(result.defects.get(k), dict) and "tolerance" in result.defects[k])
    if not rel > 0.01 * tol:
        return ""
    top = float(np.abs(mesh.V).max())
    return (f"; coordinates up to {top:.3g} are stored to {np.spacing(top):.3g} (float64), {rel:.2g} of the mean "
            f"edge, too coarse for the tolerance {tol:g}: move the mesh near the origin (its centre is at "
            f"{', '.join(f'{c:.6g}' for c in mesh.V.mean(axis=0))}) and optimize again")


def record_shape(result: OptimizeResult, mesh0: Mesh, distance: np.ndarray, diagonal: float) -> None:
    """``defects["distance"]``: max and mean distance of the result's vertices to the reference,
    ``distance (n,)`` in the mesh's units, absolute and over the reference's bbox ``diagonal``;
    ``defects["fairness"]``: the roughness (``fairness.roughness``) of ``mesh0`` (the input)
    and of the result, and their ratio (above 1: the result is rougher)."""
    from .terms.fairness import roughness

    d = np.asarray(distance, dtype=float)
    result.defects["distance"] = {"max": float(d.max(initial=0.0)), "mean": float(d.mean()) if d.size else 0.0,
                                  "max_relative": float(d.max(initial=0.0) / diagonal),
                                  "mean_relative": float(d.mean() / diagonal) if d.size else 0.0}
    before, after = roughness(mesh0), roughness(result.mesh)
    result.defects["fairness"] = {"input": before, "result": after,
                                  "ratio": float(after / before) if before > 0 else float("inf") if after > 0 else 1.0}


def _plain(v):
    """A JSON-ready scalar for numpy numbers."""
    if isinstance(v, (np.floating, np.integer, np.bool_)):
        return v.item()
    return v
