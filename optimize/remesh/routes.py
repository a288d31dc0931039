"""Two routes to a fold-free mesh: optimize the input's own mesh lines, or remesh first.

A quad mesh whose lines are far from a conjugate net (``optimize.mesh.conjugacy``)
has no fold-free PQ mesh near it: the convexity rows of the default optimizer
then hold some faces and the run ends with that diagnosis.  The paper's way
forward is to treat the input quads as a surface, remesh it along principal
directions (``optimize.remesh.quads``: a principal net is conjugate, and orthogonal
as conical and circular meshes need), and optimize the new mesh with the input
surface as the reference and a gliding boundary (``remesh.surface_to_mesh``).

``remesh``: ``"never"`` (the input's own lines only), ``"auto"`` (the remeshed
route too when the original one does not converge fold-free or the input's
lines are far from the net the target needs, ``NetDefect.far``; of two
successful routes the one closer to the input surface, the original on a tie),
``"always"`` (both routes, the remeshed one is the answer).  Every route tried
is reported.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

from ..api import optimize_mesh as _optimize_mesh  # the default optimizer (this package sits above the api)
from ..errors import ConfigError, MeshError
from ..mesh import Mesh, measures
from ..result import OptimizeResult

REMESH = ("auto", "always", "never")


@dataclass
class Route:
    """One way to the target: ``name`` (``"original"`` | ``"remeshed"``), its result (None when
    the route could not be taken), the final mesh, a note, seconds."""

    name: str
    result: OptimizeResult | None
    mesh: Mesh | None
    note: str = ""
    seconds: float = 0.0

    def as_dict(self) -> dict:
        """JSON-ready facts of the route (for reports)."""
        out = {"route": self.name, "note": self.note, "seconds": float(self.seconds)}
        r = self.result
        if r is not None:
            d = r.defects
            out.update(status=r.status, success=bool(r.success), nit=int(r.nit), faces=int(r.mesh.n_faces),
                       vertices=int(r.mesh.n_vertices), folded=int(d.get("folded", {}).get("count", 0)),
                       planarity=float(d.get("planarity", {}).get("max", float("nan"))),
                       distance=d.get("distance"), fairness=d.get("fairness"), message=r.message)
        return out

    def line(self) -> str:
        """One line for a terminal."""
        r = self.result
        if r is None:
            return f"{self.name} route: not taken ({self.note})"
        d = r.defects.get("distance") or {}
        return (f"{self.name} route: {r.status}, {r.mesh.n_faces} faces, planarity "
                f"{r.defects['planarity']['max']:.2g}, {r.defects.get('folded', {}).get('count', 0)} folded, "
                f"max distance {100 * d.get('max_relative', r.max_distance):.3g}% of the diagonal, "
                f"{self.seconds:.2f} s" + (f" ({self.note})" if self.note else ""))


def optimize_routes(mesh: Mesh, target: str = "pq", *, remesh: str = "auto", edge_length: float | None = None,
                    reference: Mesh | None = None, original: OptimizeResult | None = None,
                    optimizer=None, **kwargs) -> tuple[Route, list[Route]]:
    """Optimize ``mesh`` by the routes ``remesh`` asks for; returns ``(chosen, every route tried)``.

    edge_length : target edge length of the remeshed route (default: the input's mean edge).
    reference : the surface to stay close to (default: the input mesh itself).
    original : the original route's result when the caller has it already (not run again).
    optimizer : the callable that optimizes both routes, with the signature of
        :func:`optimize.api.optimize_mesh` (None: that function).
    kwargs : its keywords for both routes; ``fixed`` and ``glide_boundary``
        apply to the original route only (the remeshed one glides its boundary on the
        input's and fixes its corners, vertex indices of the input mean nothing there).
    Raises :class:`ConfigError` for an unknown ``remesh``.
    """
    from .quads import surface_to_mesh

    optimize_mesh = optimizer or _optimize_mesh
    if remesh not in REMESH:
        raise ConfigError(f"remesh: {remesh!r} is not known, expected one of {REMESH}")
    routes = []
    t = time.perf_counter()
    res = optimize_mesh(mesh, target, reference=reference, **kwargs) if original is None else original
    original = Route("original", res, res.mesh, "the input's own mesh lines", time.perf_counter() - t)
    routes.append(original)
    far = bool(res.defects.get("net", {}).get("far"))
    if remesh == "never" or (remesh == "auto" and res.success and not far):
        return original, routes
    rest = {k: v for k, v in kwargs.items() if k not in ("fixed", "glide_boundary", "callback")}
    h = float(edge_length) if edge_length else float(measures.edge_lengths(mesh).mean())
    t = time.perf_counter()
    try:
        glide = rest.get("method", "default") == "default"  # the paper's methods cannot glide
        quads, rres, rep = surface_to_mesh(reference if reference is not None else mesh, h, target=target,
                                           glide_boundary=glide, optimizer=optimize_mesh, **rest)
    except MeshError as exc:  # closed or several components: the remesher cannot take it
        routes.append(Route("remeshed", None, None, f"remeshing failed: {exc}", time.perf_counter() - t))
        return original, routes
    note = f"remeshed along principal directions, edge {h:.4g}"
    remeshed = Route("remeshed", rres, quads, note, time.perf_counter() - t)
    routes.append(remeshed)
    if remesh == "always" or (rres.success and not res.success):
        return remeshed, routes
    if rres.success and res.success and _dist(rres) < _dist(res):
        return remeshed, routes
    return original, routes


def _dist(res: OptimizeResult) -> float:
    return float((res.defects.get("distance") or {}).get("max_relative", res.max_distance))


def summary(routes: list[Route]) -> list[dict]:
    """``Route.as_dict`` of each route."""
    return [r.as_dict() for r in routes]


