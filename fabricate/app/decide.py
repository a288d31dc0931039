"""Which route a user's own quad mesh takes, and one paragraph that says why.

A mesh given as ``input.mesh`` with no ``optimize.target`` is a user's design whose net may or may
not allow torsion-free beams.  The routes are tried in this order, each only when the one before
did not give a buildable result (:func:`decide`):

1. conical on the mesh's own lines (the optimizer's result the stage already has);
2. conical on a remesh along the principal directions of the user's surface
   (``input.remesh: auto``, the default: :func:`optimize.remesh.routes.optimize_routes`), also when
   the own lines moved the design further than ``tolerances.closeness`` (the closer one is taken);
3. the same with the node axes solved by the optimizer (``optimize.torsion_free_beams: on``) when
   beams at the boundary (or at irregular nodes) still twist by more than ``tolerances.beam_twist_mm``;
4. PQ on the mesh's own lines: planar glass, beams that twist (the paragraph says by how much,
   where, and what would make them planar).

Of the routes that meet every beam requirement the one that moved the design least is taken; when
none does, the converged one whose beams twist least.  An explicit ``optimize.target`` is honoured: only routes of that
target are tried, and the paragraph gives the same diagnosis.  Every route tried is listed, with
its status, how far it moved the design and its worst beam twist, and the advice never names a
setting already in force.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Any

import numpy as np

log = logging.getLogger(__name__)


@dataclass
class Candidate:
    """One route's outcome: ``name``, ``target``, the optimizer's result and mesh, the worst beam
    twist (mm) and which beam (index) when the offset could be taken, and a short note."""

    name: str
    target: str
    result: Any
    mesh: Any
    twist_mm: float | None = None
    twist_beam: int | None = None
    axes: Any = None
    note: str = ""
    facts: dict = field(default_factory=dict)

    @property
    def converged(self) -> bool:
        return self.result is not None and bool(self.result.success)

    def buildable(self, twist_limit: float) -> bool:
        return self.converged and self.twist_mm is not None and self.twist_mm <= twist_limit

    def moved(self) -> tuple[float, float] | None:
        """(max distance moved relative to the diagonal, in the mesh's units), or None."""
        d = (self.result.defects or {}).get("distance") if self.result is not None else None
        return None if not d else (float(d["max_relative"]), float(d["max"]))

    def line(self) -> str:
        r = self.result
        if r is None:
            return f"{self.name}: not taken ({self.note})"
        moved = self.moved()
        text = f"{self.name}: {r.status}"
        if moved is not None:
            text += f", moved up to {moved[1]:,.0f} mm ({100 * moved[0]:.2f} %)"
        if self.twist_mm is not None:
            text += f", beams twist up to {self.twist_mm:.3g} mm"
        return text


def beam_twist(cfg, mesh, result) -> tuple[float | None, int | None]:
    """The worst beam twist (mm) of ``mesh`` offset as the run will offset it, and its beam index;
    ``(None, None)`` when the offset cannot be taken (a stalled mesh that is not PQ)."""
    from fabricate.offset import offset_structure
    from optimize.errors import ConicalFabError

    try:
        s = offset_structure(mesh, cfg.layer_distances(), axes=getattr(result, "beam_axes", None),
                             flip=cfg.offset.flip, tol=cfg.tolerances.to_tolerances())
    except (ConicalFabError, ValueError, FloatingPointError) as exc:
        log.info("route check: no offset of %s: %s", mesh.name, exc)
        return None, None
    twist = np.abs(np.asarray(s.beam_twist_mm, dtype=float))
    if not twist.size:
        return 0.0, None
    i = int(np.argmax(twist))
    return float(twist[i]), i


def decide(cfg, inp, result, kwargs: dict, *, auto_target: bool, remesh: str) -> tuple[Candidate, list[Candidate], str]:
    """The route the run takes for ``inp.mesh`` (mm): ``(chosen, every candidate tried, paragraph)``.

    result : the optimizer's result on the mesh's own lines (``inp.target``), already computed;
    kwargs : the optimizer's keywords (:func:`fabricate.app.stages.optimizer_call`);
    auto_target : no ``optimize.target`` was given (PQ is then a fallback);
    remesh : ``input.remesh`` (``auto`` | ``always`` | ``never``).
    """
    from optimize.api import optimize_mesh
    from optimize.errors import ConfigError, MeshError
    from optimize.remesh.routes import optimize_routes

    limit = float(cfg.tolerances.beam_twist_mm)
    target = inp.target
    tried: list[Candidate] = []

    def judge(c: Candidate) -> Candidate:
        if c.result is not None and c.mesh is not None and c.result.success:
            c.twist_mm, c.twist_beam = beam_twist(cfg, c.mesh, c.result)
        tried.append(c)
        log.info("route %s", c.line())
        return c

    own = judge(Candidate("own lines", target, result, result.mesh))
    best = own
    far = own.moved() is not None and own.moved()[0] > cfg.tolerances.closeness  # moved beyond the tolerance
    def remeshed(name: str, **kw) -> Candidate:
        try:
            _, routes = optimize_routes(inp.mesh, target, remesh="always", original=result, **kw)
        except (ConfigError, MeshError) as exc:  # the remesher cannot take this surface (which side is in)
            return Candidate(name, target, None, None, note=f"remeshing failed: {exc}")
        re = next(r for r in routes if r.name == "remeshed")
        return Candidate(name, target, re.result, re.mesh, note=re.note)

    if (not own.buildable(limit) or far or remesh == "always") and remesh != "never":
        best = _better(best, judge(remeshed("remeshed along principal directions", **kwargs)), limit)
    tfb = kwargs.get("torsion_free_beams")
    if not best.buildable(limit) and best.converged and tfb is not None and tfb is not True and target != "pq":
        on = dict(kwargs, torsion_free_beams=True)
        if best is own:
            res = optimize_mesh(inp.mesh, target, reference=None, **on)
            c = Candidate("own lines, node axes solved with the mesh", target, res, res.mesh)
        else:
            c = remeshed("remeshed, node axes solved with the mesh", **on)
        best = _better(best, judge(c), limit)
    if auto_target and not best.converged and target != "pq":
        pq = dict(kwargs)
        pq.pop("torsion_free_beams", None)
        res = optimize_mesh(inp.mesh, "pq", **pq)
        best = _better(best, judge(Candidate("PQ on own lines", "pq", res, res.mesh)), limit)
    return best, tried, paragraph(best, tried, limit, auto_target=auto_target, remesh=remesh, target=target)


def _better(a: Candidate, b: Candidate, limit: float) -> Candidate:
    """The better of two routes: buildable before converged before not; of two buildable ones the one
    that moved the design less, of two others the one whose beams twist less (``a`` on a tie: the
    earlier route)."""
    def key(c: Candidate):
        moved = c.moved()
        moved = moved[0] if moved is not None else float("inf")
        twist = c.twist_mm if c.twist_mm is not None else float("inf")
        return (not c.buildable(limit), not c.converged) + ((moved,) if c.buildable(limit) else (twist, moved))
    return b if key(b) < key(a) else a


def paragraph(best: Candidate, tried: list[Candidate], limit: float, *, auto_target: bool, remesh: str,
              target: str) -> str:
    """One paragraph for the top of the output and the report: what was reached, how, what else was
    tried, and what would help (never a setting already in force)."""
    from fabricate.cad.parts import part_ids

    moved = best.moved()
    where = f", moving the design up to {moved[1]:,.0f} mm ({100 * moved[0]:.2f} % of its diagonal)" if moved else ""
    if best.buildable(limit):
        head = (f"Route: {best.target} by {best.name}{where}: planar glass, every beam planar to "
                f"{best.twist_mm:.2g} mm.")
    elif best.converged and best.twist_mm is not None:
        beam = ""
        if best.twist_beam is not None:
            n_edges = len(best.mesh.topology.edges)
            beam = f" (worst {part_ids('beam', np.array([best.twist_beam, n_edges - 1]))[0]})"
        head = (f"Route: {best.target} by {best.name}{where}: planar glass, but beams twist up to "
                f"{best.twist_mm:.3g} mm{beam}, more than the {limit:g} mm a shop takes.")
        if best.target == "pq" and not auto_target:
            head += (" Beams are planar only on a conical mesh: optimize.target: conical (or no target) would "
                     "look for one near this design.")
        elif best.target == "pq":
            head += (" Beams are planar only on a conical mesh: no conical mesh was reached near this design"
                     + ("" if remesh != "never" else "; input.remesh: auto would also try a remesh along "
                        "principal directions") + ".")
    else:
        status = best.result.status if best.result is not None else "not taken"
        head = f"Route: no route reached its target; the nearest is {best.name} ({status}){where}."
    others = [c.line() for c in tried if c is not best]
    text = head + (" Tried: " + "; ".join(others) + "." if others else "")
    if not best.converged:  # what would help: never a setting already in force
        taken = any(c.name.startswith("remeshed") and c.result is not None for c in tried)
        if remesh == "never":
            text += " What may help: input.remesh: auto (a remesh along the principal directions of the design)."
        elif taken:
            text += (" Neither the design's own lines nor its principal directions lead to a nearby "
                     f"{target} mesh: a smoother design, or a finer or coarser net, may.")
        else:
            text += (f" The design's own lines lead to no nearby {target} mesh, and the remesh along its principal "
                     "directions could not be made (why: above).")
    if not auto_target:
        text += f" (optimize.target: {target} was asked for; other targets were not tried.)"
    return text
