"""The glazing gasket on a beam's flat top face: the fold between the two panels a beam carries and the
height step it puts across each gasket (``gasket.csv``, the run's warning beyond a limit).

A stock section (RHS, SHS, I) has a flat top face; the glass sits on a gasket on it, on each side of the
joint.  Per beam (mesh edge ``e``, its axis ``u`` from node axis to node axis along the glass edge):

- the top face: the plane through the glass edge perpendicular to the beam's plane (the web's plane,
  which holds the node axes at both ends); its unit normal ``t`` is the node axes' mean direction
  (beams toward glass) with its part along ``u`` taken out;
- ``n_a``, ``n_b``: the unit normals of the two panels on the beam (the mesh faces across edge ``e``,
  ``a`` the first of ``topology.edge_faces``), turned to the glass side (``n . t > 0``);
- ``fold_deg``: the angle between the two panels' planes, ``arccos(n_a . n_b)`` (0: flat; the steel
  cut list's ``dihedral_deg`` is 180 minus it);
- ``tilt_a_deg``, ``tilt_b_deg``: the angle between each panel and the top face, ``arccos(n . t)``
  (on a conical mesh the beam plane bisects the panels: each tilt is half the fold);
- ``step_a_mm``, ``step_b_mm``: ``bite_mm * tan(tilt)``, how much higher the panel's underside stands
  above the flat top at one edge of its gasket than at the other, across the gasket's bite (the width
  the panel edge bears on, ``outputs.gasket.bite_mm``): what the gasket's compression takes up.

A beam is flagged when its fold exceeds ``outputs.gasket.max_fold_deg`` (a beam on the roof's edge,
with one panel: twice that panel's tilt, the fold of a beam whose top bisects it).  The default, 2 deg,
tilts each panel by 1 deg on its gasket: a 0.35 mm step across a 20 mm bite, a small part of the
millimetre or so that a glazing gasket a few mm high compresses, so it bears along both its lips; a
larger fold asks for a gasket that takes the rotation or a top face that follows the panels.  A flag
is a warning in the run, never a failure.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

GASKET = {"bite_mm": 20.0, "max_fold_deg": 2.0}
"""The gasket when the config does not say (``outputs.gasket``; the limit: see the module text)."""
COLUMNS = ("id", "edge", "panels", "fold_deg", "tilt_a_deg", "tilt_b_deg", "bite_mm", "step_a_mm", "step_b_mm",
           "flags")


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-300)


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Degrees between unit vectors ``a``, ``b`` (``(..., 3)``, broadcast), exact near 0 (``atan2``)."""
    return np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("...i,...i->...", a, b)))


def options(gasket: dict | None) -> tuple[float, float]:
    """``(bite mm, max fold deg)`` of an ``outputs.gasket`` mapping (None: :data:`GASKET`)."""
    o = {**GASKET, **{k: v for k, v in (gasket or {}).items() if v is not None}}
    return float(o["bite_mm"]), float(o["max_fold_deg"])


def gasket_table(parts, gasket: dict | None = None) -> dict:
    """Per beam (sorted by edge): ``ids`` (b,) beam ids, ``edge (b,)``, ``panels`` [(pa, pb)] panel ids
    (``-`` where none), ``fold (b,)`` deg (NaN with one panel), ``tilt (b, 2)`` deg (NaN where no panel),
    ``step (b, 2)`` mm, ``judged (b,)`` deg (the fold, or twice the one panel's tilt), ``flagged (b,)``
    bool (``judged > limit``), ``bite``, ``limit`` (see the module text)."""
    from optimize.mesh.measures import face_normals

    from fabricate.cad.parts import part_ids, unit_id

    from .schedules import beam_units

    bite, limit = options(gasket)
    mesh = parts.mesh
    gs = beam_units(parts) if mesh is not None else []
    if not gs:
        z = np.zeros(0)
        return {"ids": [], "edge": z.astype(int), "panels": [], "fold": z, "tilt": z.reshape(0, 2),
                "step": z.reshape(0, 2), "judged": z, "flagged": z.astype(bool), "bite": bite, "limit": limit}
    C = np.concatenate([g.centre_line if g.centre_line is not None else g.vertices[:, :4] for g in gs])
    edge = np.concatenate([g.element for g in gs])
    ids = [unit_id(i) for g in gs for i in g.ids]
    order = np.argsort(edge, kind="stable")
    C, edge, ids = C[order], edge[order], [ids[i] for i in order.tolist()]
    u = _unit(C[:, 1] - C[:, 0])
    d = (C[:, 0] - C[:, 3]) + (C[:, 1] - C[:, 2])              # the node axes, beams toward glass
    t = _unit(d - np.einsum("pi,pi->p", d, u)[:, None] * u)
    EF = mesh.topology.edge_faces[edge]                          # (b, 2), -1 on the boundary
    N = face_normals(mesh)[np.maximum(EF, 0)]                    # (b, 2, 3)
    N *= np.where(np.einsum("pki,pi->pk", N, t) < 0, -1.0, 1.0)[..., None]
    has = EF >= 0
    tilt = np.where(has, _angle(N, t[:, None]), np.nan)
    fold = np.where(has.all(axis=1), _angle(N[:, 0], N[:, 1]), np.nan)
    step = bite * np.tan(np.radians(tilt))
    judged = np.where(np.isnan(fold), 2 * np.nanmax(np.where(has, tilt, -np.inf), axis=1), fold)
    pid = part_ids("panel", np.arange(mesh.n_faces))
    panels = [tuple(pid[f] if f >= 0 else "-" for f in row) for row in EF.tolist()]
    return {"ids": ids, "edge": edge, "panels": panels, "fold": fold, "tilt": tilt, "step": step,
            "flagged": judged > limit, "judged": judged, "bite": bite, "limit": limit}


def _num(x: float, fmt: str = "{:.2f}") -> str:
    return "" if not np.isfinite(x) else fmt.format(x)


def write_gasket_schedule(parts, path, gasket: dict | None = None) -> dict:
    """Write ``gasket.csv`` (atomic): one row per beam (see the module text).  Returns facts: ``file,
    bytes, rows, max_fold_deg, max_step_mm, flagged, seconds``."""
    from .schedules import _write

    t0 = time.perf_counter()
    path = Path(path)
    g = gasket_table(parts, gasket)

    def rows():
        for k, bid in enumerate(g["ids"]):  # one row per beam
            what = "fold" if np.isfinite(g["fold"][k]) else "one panel: twice its tilt"
            flag = (f"{what} {g['judged'][k]:.2f} deg beyond {g['limit']:g} deg (outputs.gasket.max_fold_deg)"
                    if g["flagged"][k] else "")
            yield (bid, int(g["edge"][k]), " ".join(g["panels"][k]), _num(g["fold"][k]), _num(g["tilt"][k, 0]),
                   _num(g["tilt"][k, 1]), f"{g['bite']:g}", _num(g["step"][k, 0]), _num(g["step"][k, 1]), flag)
    n = _write(path, COLUMNS, rows())
    fold = g["fold"][np.isfinite(g["fold"])]
    step = g["step"][np.isfinite(g["step"])]
    return {"file": path.name, "bytes": path.stat().st_size, "rows": n,
            "max_fold_deg": round(float(fold.max()), 3) if fold.size else None,
            "max_step_mm": round(float(step.max()), 3) if step.size else None,
            "flagged": int(g["flagged"].sum()), "seconds": time.perf_counter() - t0}


def gasket_measures(parts, gasket: dict | None = None) -> dict:
    """``{"gasket_fold": ...}``: the fold per beam (one panel: twice its tilt) against
    ``outputs.gasket.max_fold_deg``, an information measure (a warning beyond it, never a failure)."""
    from fabricate.report.measures import entry

    g = gasket_table(parts, gasket)
    if not len(g["ids"]):
        return {}
    step = np.nan_to_num(np.nanmax(np.where(np.isfinite(g["step"]), g["step"], -np.inf), axis=1), neginf=0.0)
    return {"gasket_fold": entry(g["judged"], g["limit"], "deg", "edge", ids=g["edge"], extra={"step_mm": step},
                                 what="fold between the two panels on a beam (0 flat; an edge beam: twice its "
                                      "panel's tilt), which the gasket on a flat top face takes; "
                                      "limit outputs.gasket.max_fold_deg")}
