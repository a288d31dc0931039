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

STATUSES = ("converged", "folded", "stalled", "max_iter", "diverged")


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
        ``"stalled"`` (no progress) | ``"max_iter"`` | ``"diverged"`` (the last
        good iterate is returned).
    message : str
        One sentence saying why the run stopped, with the figures.
    nit : int
        Iterations done.
    history : list of dict
        One dict per iteration: ``planarity``, ``conical``, ``circular``
        (max defects), ``fairness``, ``closeness`` (energies), ``step``,
        ``residual`` and solver details.
    defects : dict
        Final measures (``measures.summary``-like).
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
        over = [f"{k} {v['max']:.3g} > {v['tolerance']:.3g}" for k, v in self.defects.items()
                if isinstance(v, dict) and v.get("ok") is False and "max" in v and "tolerance" in v]
        folded = self.defects.get("folded", {}).get("count", 0)
        facts = ", ".join(over + ([f"{folded} folded face(s)"] if folded else [])) or "no defect over tolerance"
        raise ConvergenceError(f"{self.mesh.name}: {self.method}/{self.target} ended {self.status} after "
                               f"{self.nit} iteration(s) ({facts}): {self.message}")

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
    """The one fold check of every method: record ``defects["folded"]`` (faces convex at
    ``V0 (n, 3)``, the input positions, that are dented, flipped or collapsed in
    ``result.mesh``: :func:`optimize.mesh.measures.folded_faces`) and turn a ``converged``
    run with any of them into ``folded`` (not a success); ``advice`` ends the message;
    ``fold`` is ``Tolerances.fold``.
    Returns ``result`` (updated in place; calling it twice changes nothing more)."""
    folded = np.nonzero(measures.folded_faces(result.mesh, result.mesh.V, V0, fold))[0]
    result.defects["folded"] = {"count": int(len(folded)), "faces": folded[:20].tolist()}
    if len(folded) and result.status == "converged":
        result.status, result.success = "folded", False
        result.message = (f"{result.message}, but {len(folded)} face(s) that were convex became dented, "
                          f"flipped or collapsed (first: {folded[:5].tolist()})" + (f"; {advice}" if advice else ""))
    return result


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
