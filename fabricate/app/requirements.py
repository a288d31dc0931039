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
from fabricate.report.measures import warnings  # noqa: F401 - re-exported (the headline's warning lines)


def default_requirements(target: str, closeness_mm: float | None = None) -> tuple[str, ...]:
    """The shop defaults for a run with optimization ``target``; ``closeness`` too when the config
    gives a limit in mm (``tolerances.closeness_mm``)."""
    extra = {"conical": ("conical", "beam_planarity"), "circular": ("circular",)}.get(target, ())
    return ("planarity", "folded", "beam_twist") + extra + (("closeness",) if closeness_mm is not None else ())


def apply_requirements(measures: dict, structure, requirements, target: str, beam_twist_mm: float,
                       closeness_mm: float | None = None) -> dict:
    """``measures`` with ``beam_twist`` added and ``enforced`` / ``role`` set from ``requirements``
    (a list of names, or None for :func:`default_requirements`); a measure that ``requirements``
    cannot name keeps the ``enforced`` its stage gave it.  Returns the same dict."""
    from fabricate.report.measures import entry

    if structure is not None and len(getattr(structure, "beam_twist_mm", ())):
        twist = np.abs(np.asarray(structure.beam_twist_mm, dtype=float))
        measures["beam_twist"] = entry(twist, beam_twist_mm, "mm", "beam", extra={"mm": twist},
                                       what="twist of every beam (boundary ones too): how far a corner of its "
                                            "quad is off the plane of the other three, mm")
    wanted = set(default_requirements(target, closeness_mm) if requirements is None else requirements)
    if closeness_mm is not None:  # a limit in mm is asked for: always a requirement
        wanted.add("closeness")
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
