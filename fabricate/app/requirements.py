"""Which measures are requirements (they fail the run, exit 3) and which are information (warnings).

``tolerances.requirements`` in the config names the requirements; ``null``
(the default) takes the shop defaults of :func:`default_requirements`:

- ``planarity`` and ``folded``: the glass is flat and cuttable;
- ``beam_twist``: no beam twists by more than ``tolerances.beam_twist_mm``
  (1 mm: a plate that twists by a millimetre does not sit on its panels);
- ``conical`` and ``beam_planarity`` (interior beams torsion-free, relative)
  for a conical target, ``circular`` for a circular one: what the run was
  asked to make.

Every other measure is information: when it exceeds its tolerance it is a
warning in the headline with its value in mm, never a red FAIL under a green
banner.  :func:`apply_requirements` rewrites ``enforced`` and adds ``role``
on the measures of :func:`fabricate.report.measures.collect_measures`, and
adds ``beam_twist`` (mm, every beam, boundary ones too).
"""
from __future__ import annotations

import numpy as np

from fabricate.app.config import MEASURE_NAMES as MEASURES  # noqa: F401  (the names requirements accepts)


def default_requirements(target: str) -> tuple[str, ...]:
    """The shop defaults for a run with optimization ``target``."""
    extra = {"conical": ("conical", "beam_planarity"), "circular": ("circular",)}.get(target, ())
    return ("planarity", "folded", "beam_twist") + extra


def apply_requirements(measures: dict, structure, requirements, target: str, beam_twist_mm: float) -> dict:
    """``measures`` with ``beam_twist`` added and ``enforced`` / ``role`` set from ``requirements``
    (a list of names, or None for :func:`default_requirements`); a measure that ``requirements``
    cannot name keeps the ``enforced`` its stage gave it.  Returns the same dict."""
    from fabricate.report.measures import entry

    if structure is not None and len(getattr(structure, "beam_twist_mm", ())):
        twist = np.abs(np.asarray(structure.beam_twist_mm, dtype=float))
        measures["beam_twist"] = entry(twist, beam_twist_mm, "mm", "beam", extra={"mm": twist},
                                       what="twist of every beam (boundary ones too): how far a corner of its "
                                            "quad is off the plane of the other three, mm")
    wanted = set(default_requirements(target) if requirements is None else requirements)
    other_target = {"conical", "circular"} - {target}
    for name, m in measures.items():
        if name not in MEASURES:  # a measure with its own rule (offset_turned_over; the structure
            m["enforced"] = bool(m.get("enforced"))  # check, enforced by structure.check): kept
            m["role"] = "requirement" if m["enforced"] else "information"
            continue
        m["enforced"] = name in wanted
        m["role"] = ("requirement" if name in wanted else "reported" if name in other_target
                     else "information")
    return measures


def warnings(measures: dict, limits: dict | None = None) -> list[str]:
    """One line per information measure beyond its tolerance, with its value in mm where it has one
    (not the defect of a target the run did not ask for: ``role`` reported), and per shop limit
    (``parts.report["limits"]``) some part breaks, with the ids."""
    out = []
    for name, m in measures.items():
        if m.get("enforced") or m.get("pass") is not False or m.get("role") == "reported":
            continue
        mm = next((m[k] for k in ("max_mm", "max_twist_mm") if m.get(k) is not None), None)
        deg = m.get("max_deg")
        value = (f"{mm:.3g} mm" if mm is not None else f"{deg:.3g} deg" if deg is not None
                 else f"{m['max']:.3g} {m.get('unit', '')}".strip())
        out.append(f"{name} {value} (max {m['max']:.3g} {m.get('unit', '')} > tolerance {m['tolerance']:.3g})")
    for key, v in (limits or {}).items():
        if v.get("count"):
            ids = ", ".join(v["ids"][:12]) + (" ..." if v["count"] > 12 else "")
            out.append(f"{v['count']} part(s) beyond the {key} limit ({v['limit']}): {ids}")
    return out
