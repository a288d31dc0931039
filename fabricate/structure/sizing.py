"""Sizing help: the lightest candidate section per beam group that passes the check.

Groups (``structure.sizing.group_by``): ``all`` beams together, or ``boundary`` (beams on the
mesh boundary) and ``interior``.  Each round solves the frame with the current sections, then
picks per group the lightest candidate whose utilization and beam deflection, estimated from
the current forces (the utilization of :mod:`fabricate.structure.results` with the candidate's
``A, Wy, Wz`` and buckling factor; the deflection scaled by the larger ratio of ``Iy`` or ``Iz``),
pass for every beam of the group, and whose section class (EN 1993-1-1 Table 5.2) under the forces
at each beam's point nearest class 4 is not 4; the forces change with the stiffnesses and the
self-weight, so the rounds repeat until the choice is stable and the re-solved frame passes (no
class 4 beam either).  A group whose choice failed a full solve never goes back to that section
or a lighter one, so the rounds end.  The answer is always the result of a full solve with the
chosen sections, never the estimate.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from optimize.errors import ConfigError

from .check import check_structure, configured_section
from .options import ALPHA, GRADES
from .results import ROUND_OFF, buckling_factor, utilization
from .sections import classify


@dataclass(frozen=True, eq=False)
class Sizing:
    """The outcome: ``groups {name: (e_g,) element indices}``, ``chosen {group: section name}``,
    ``check`` (the final solve), masses in kg, ``rounds``, ``passes``, per group max utilization,
    ``excluded``: the candidates that are class 4 in some beam under the final forces (an estimate)."""

    groups: dict
    chosen: dict
    check: object
    configured_mass_kg: float
    sized_mass_kg: float
    configured_section: str
    rounds: int
    passes: bool
    utilization: dict = field(default_factory=dict)
    history: list = field(default_factory=list)
    excluded: list = field(default_factory=list)

    @property
    def saved_kg(self) -> float:
        return self.configured_mass_kg - self.sized_mass_kg

    def as_dict(self) -> dict:
        return {"configured_section": self.configured_section, "chosen": self.chosen,
                "beams": {g: int(len(ix)) for g, ix in self.groups.items()},
                "max_utilization": self.utilization, "passes": self.passes, "rounds": self.rounds,
                "configured_mass_kg": round(self.configured_mass_kg, 1), "sized_mass_kg": round(self.sized_mass_kg, 1),
                "saved_kg": round(self.saved_kg, 1),
                "saved_percent": round(100.0 * self.saved_kg / self.configured_mass_kg, 1)
                if self.configured_mass_kg > 0 else 0.0, "history": self.history,
                "class_4_under_the_final_forces": self.excluded}


def beam_groups(structure, group_by: str) -> dict[str, np.ndarray]:
    """``{group name: element indices}`` for ``group_by`` ``all`` | ``boundary``."""
    e = len(structure.edges)
    if group_by == "all":
        return {"all": np.arange(e)}
    b = np.asarray(structure.mesh.topology.is_boundary_edge)
    out = {"boundary": np.nonzero(b)[0], "interior": np.nonzero(~b)[0]}
    return {k: v for k, v in out.items() if v.size}


def size_sections(structure, options, spec) -> Sizing:
    """Pick the lightest passing section per group from ``options.sizing.sections``."""
    if not options.sizing.sections:
        raise ConfigError("structure.sizing.sections: empty, expected a list of candidate sections "
                          "(e.g. - {shape: rhs, depth: 200, width: 100, web: 6})")
    base = configured_section(options, spec, structure)
    cands = sorted({s.properties("structure.sizing.sections").name: s.properties("structure.sizing.sections")
                    for s in options.sizing.sections}.values(), key=lambda s: (s.A, -s.Iy))
    fy, alpha, fy_k = options.fy, ALPHA[options.buckling_curve], GRADES[options.grade]
    groups = beam_groups(structure, options.sizing.group_by)
    e = len(structure.edges)
    first = check_structure(structure, options, spec)
    configured_mass = first.frame.steel_mass_kg(spec.density_steel)
    pick = {g: len(cands) - 1 for g in groups}  # start from the heaviest candidate
    floor = {g: 0 for g in groups}              # lighter ones failed a full solve
    history: list = []
    chk = None
    for rounds in range(1, options.sizing.max_rounds + 1):
        section_of = np.zeros(e, dtype=np.int64)
        for g, ix in groups.items():
            section_of[ix] = pick[g]
        chk = check_structure(structure, options, spec, sections=cands, section_of=section_of)
        checked = dict(pick)
        r = chk.results
        passes = chk.passes()
        history.append({"round": rounds, "chosen": {g: cands[pick[g]].name for g in groups},
                        "max_utilization": round(chk.max_utilization, 4), "passes": passes})
        if not passes:
            for g in _failing_groups(chk, groups):
                floor[g] = max(floor[g], pick[g] + 1)
        new = {}
        for g, ix in groups.items():
            cur = cands[pick[g]]
            N, Ms, Mw = r.N_kN[ix] * 1e3, r.M_strong_kNm[ix] * 1e6, r.M_weak_kNm[ix] * 1e6
            Nc, Mc = r.class_N_kN[ix] * 1e3, r.class_M_kNm[ix] * 1e6
            defl = r.deflection_mm[ix] / r.deflection_limit_mm[ix]
            L = chk.frame.lengths()[ix] * options.buckling_length_factor
            ok = [c for c, s in enumerate(cands)
                  if c >= floor[g]
                  and utilization(N, Ms, Mw, s.A, s.Wy, s.Wz,
                                  buckling_factor(s.A, min(s.Iy, s.Iz), L, options.elastic_modulus, fy, alpha),
                                  fy).max() <= 1.0
                  and (defl * max(cur.Iy / s.Iy, cur.Iz / s.Iz)).max() <= 1.0
                  and not (classify(s, fy_k, Nc, Mc, Mw, _floor(s, N, Ms, Mw)).cls == 4).any()]
            new[g] = ok[0] if ok else min(max(floor[g], pick[g]), len(cands) - 1)
        if new == pick and (passes or all(floor[g] >= len(cands) for g in groups if g in _failing_groups(chk, groups))):
            break  # stable and passing, or the heaviest candidate does not pass: say so
        pick = new
    util = {g: round(float(chk.results.utilization[ix].max(initial=0.0)), 4) for g, ix in groups.items()}
    r = chk.results
    forces = [(r.class_N_kN[ix] * 1e3, r.class_M_kNm[ix] * 1e6, r.M_weak_kNm[ix] * 1e6, r.N_kN[ix] * 1e3,
               r.M_strong_kNm[ix] * 1e6) for ix in groups.values()]
    slender = [s.name for s in cands
               if any((classify(s, fy_k, Nc, Mc, Mw, _floor(s, N, Ms, Mw)).cls == 4).any()
                      for Nc, Mc, Mw, N, Ms in forces)]
    return Sizing(groups=groups, chosen={g: cands[checked[g]].name for g in groups}, check=chk,
                  configured_mass_kg=configured_mass, sized_mass_kg=chk.frame.steel_mass_kg(spec.density_steel),
                  configured_section=base.name, rounds=rounds, passes=chk.passes(), utilization=util,
                  history=history, excluded=slender)


def _floor(s, N, Ms, Mw) -> np.ndarray:
    """The round-off stress (MPa) of section ``s`` under a beam's governing forces (:data:`ROUND_OFF`)."""
    return ROUND_OFF * (np.abs(N) / s.A + np.abs(Ms) * s.h / s.Iy + np.abs(Mw) * s.b / s.Iz)


def _failing_groups(chk, groups) -> set[str]:
    r = chk.results
    bad = (r.utilization > 1.0) | (chk.deflection_ratio() > 1.0) | (r.section_class.cls == 4)
    if r.displacement_mm.max(initial=0.0) > r.displacement_limit_mm:
        bad[:] = True  # the whole structure is too soft: every group moves up
    return {g for g, ix in groups.items() if bad[ix].any()}
