"""Glass check of every panel after EN 16612:2019 (and DIN 18008-1/-2 where EN 16612 leaves a rule open).

Per glass unit, for its real outline (any convex polygon) simply supported on
all its edges by the beams (:mod:`fabricate.structure.plate`, linear plate
theory), under the structure's load cases and combinations:

- **loads** on the panel normal (kN/m2 -> N/mm2): each pane's own weight
  (``glass_unit_weight`` for the plies, the interlayer's density for the
  interlayers) times the cosine of the slope; snow (per m2 of plan) on the
  outer pane, times the cosine squared of the slope, where the outer face looks
  up; wind pressure toward the beams and suction away from them on the outer
  pane.  ``finishes`` (fixings, gaskets) bear on the beams, not on the glass;
  ``self_weight`` is the steel's.
- **laminated panes** by their effective thicknesses (EN 16612:2019 Annex D,
  the shear transfer coefficient omega of the interlayer's stiffness family and
  the load's duration): ``h_ef,w^3 = sum h_k^3 + 12 omega sum h_k h_m,k^2`` for
  the deflection, ``h_j,ef,sigma^2 = h_ef,w^3 / (h_j + 2 omega h_m,j)`` for the
  stress of ply ``j`` (``h_m,k`` the distance of ply ``k``'s mid-plane from the
  laminate's);
- **insulating units**: the isochore pressure ``p0 = c1 dT - dp_met + c2 dH``
  (c1 = 0.34 kPa/K, c2 = 0.012 kPa/m; summer and winter as DIN 18008-1 Table 3)
  and every external load shared between the panes by the gas (DIN 18008-1
  Annex A): stiffness shares ``delta_k = D_k / (D_o + D_i)`` and the insulating
  unit factor ``phi = 1 / (1 + p_atm (v_o + v_i) / V)``, ``v_k`` the volume a
  pane sweeps per unit pressure and ``V`` the cavity's: for a rectangle this is
  DIN's ``1 / (1 + (a / a*)^4)``, here from the plate solution of the real
  outline;
- **resistance** (EN 16612:2019 eq. (5)):
  ``f_g,d = k_e k_mod k_sp f_g,k / gamma_M,A + k_v (f_b,k - f_g,k) / gamma_M,v``, f_g,k = 45 MPa,
  f_b,k = 70 (heat-strengthened, EN 1863-1), 120 (toughened, EN 12150-1 / EN 14179-1), 45 / 75 on an
  enamelled face; ``k_mod = 0.663 t^(-1/16)`` (t in hours, at most 1) of the shortest load in the
  combination (DIN 18008-1 8.3.7); the consequence class by ``K_FI`` on the actions (EN 1990 Annex B);
- **deflection** of each pane under the SLS combinations against ``span / deflection_limit``, the span
  the diameter of the outline's largest inscribed circle (a rectangle's shorter side);
- **overhead glazing** (more than 10 deg from vertical): the build-up's warnings
  (:meth:`fabricate.cad.glass.BuildUp.overhead_warnings`: a laminated lower pane, not toughened in
  every ply) and the interlayer DIN 18008-2 asks (PVB at least 0.76 mm); the residual capacity of the
  broken lower pane is stated, not computed.

Not checked: large deflections (membrane action; linear theory overestimates
stress and deflection of thin panes), point fixings, edge stresses of annealed
glass under thermal load (thermal breakage), impact, glass under line loads and
barrier loads, and the post-breakage test of DIN 18008-2 Annex B.
"""
from __future__ import annotations

import csv
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from optimize.errors import ConfigError

from ..fields import check_fields, option
from .plate import RINGS, PlateResponse, solve_plate

E_GLASS = 70000.0
"""Young's modulus of soda lime silicate glass, MPa (EN 572-1)."""
NU_GLASS = 0.23
"""Poisson's ratio of glass (EN 572-1)."""
F_GK = 45.0
"""Characteristic bending strength of annealed glass, MPa (EN 572-1, EN 16612)."""
F_BK = {"float": F_GK, "heat-strengthened": 70.0, "toughened": 120.0, "toughened-heat-soaked": 120.0}
"""Characteristic bending strength by heat treatment, MPa (EN 1863-1, EN 12150-1, EN 14179-1)."""
F_BK_ENAMEL = {"float": F_GK, "heat-strengthened": 45.0, "toughened": 75.0, "toughened-heat-soaked": 75.0}
"""The same on an enamelled face (EN 1863-1, EN 12150-1)."""
K_FI = {"CC1": 0.9, "CC2": 1.0, "CC3": 1.1}
"""Factor on the actions by consequence class (EN 1990 Annex B, Table B3)."""
C1_KPA_K, C2_KPA_M = 0.34, 0.012
"""Isochore pressure per kelvin and per metre of altitude, kPa (DIN 18008-1 Annex A)."""
THICKNESS_TOL = ((6.0, 0.2), (12.0, 0.3), (15.0, 0.5), (25.0, 1.0))
"""EN 572-2 thickness tolerance of float glass: up to 6 mm +-0.2, 8-12 +-0.3, 15 +-0.5, 19-25 +-1.0 mm."""
KMOD_MAX = 1.0
CASE_DURATION = {"self_weight": "permanent", "glass": "permanent", "finishes": "permanent", "snow": "snow",
                 "wind_pressure": "wind", "wind_suction": "wind", "climate_summer": "climate",
                 "climate_winter": "climate"}
"""The load duration class of each load case."""
OMEGA = {0: {"wind": 0.0, "climate": 0.0, "snow": 0.0, "permanent": 0.0},
         1: {"wind": 0.1, "climate": 0.0, "snow": 0.0, "permanent": 0.0},
         2: {"wind": 0.3, "climate": 0.1, "snow": 0.1, "permanent": 0.0},
         3: {"wind": 0.7, "climate": 0.3, "snow": 0.3, "permanent": 0.1}}
"""Shear transfer coefficient omega by interlayer stiffness family (EN 16613:2019, EN 16612:2019 Annex D)
and load duration class; family 0 is no shear transfer."""
ON_GLASS = ("glass", "snow", "wind_pressure", "wind_suction")
"""The structure's load cases that load the glass (the others bear on the beams)."""
OVERHEAD_PVB_MM = 0.76
"""DIN 18008-2: the PVB of overhead laminated safety glass is at least 0.76 mm."""
CLIMATE_NOTE = "climatic loads: isochore pressure shared by the gas (DIN 18008-1 Annex A)"


@dataclass(frozen=True, kw_only=True)
class GlassOptions:
    """The glass check's options (``structure.glass``)."""

    check: Literal["off", "report", "enforce"] = option("report", help="off skips it; enforce fails the run")
    consequence_class: Literal["CC1", "CC2", "CC3"] = option("CC2", help="EN 1990 Annex B: K_FI 0.9 / 1.0 / 1.1")
    gamma_m_a: float = option(1.8, ge=1.0, le=5.0, help="gamma_M,A of annealed glass (EN 16612)")
    gamma_m_v: float = option(1.2, ge=1.0, le=5.0, help="gamma_M,v of the prestress (EN 16612)")
    k_v: float = option(1.0, gt=0, le=1.0, help="strengthening factor: 1.0 horizontal, 0.6 vertical toughening")
    k_e: float = option(1.0, gt=0, le=1.0, help="edge factor (the largest stress is inside the pane)")
    k_sp: float = option(1.0, gt=0, le=1.0, help="surface profile factor: 1.0 float glass")
    thickness: Literal["nominal", "minimum"] = option("nominal", help="ply thickness: nominal or minus the "
                                                      "EN 572-2 tolerance")
    pvb_family: int = option(1, ge=0, le=3, help="EN 16613 stiffness family of the PVB")
    sgp_family: int = option(3, ge=0, le=3, help="EN 16613 stiffness family of the SGP (ionoplast)")
    omega: float | None = option(None, ge=0, le=1.0, help="one shear transfer coefficient for every load; "
                                 "null: by family and duration")
    deflection_limit: float = option(100.0, gt=0, le=10000.0, help="span / n (DIN 18008-2 overhead: 100)")
    duration_permanent_h: float = option(438000.0, gt=0, unit="h", help="50 years")
    duration_snow_h: float = option(504.0, gt=0, unit="h", help="3 weeks (EN 16613 Table 4)")
    duration_climate_h: float = option(11.0, gt=0, unit="h", help="daily temperature variation")
    duration_wind_h: float = option(1.0 / 6.0, gt=0, unit="h", help="10 min")
    summer_dt: float = option(20.0, ge=-100, le=100, unit="K", help="DIN 18008-1 Table 3")
    winter_dt: float = option(-25.0, ge=-100, le=100, unit="K", help="DIN 18008-1 Table 3")
    summer_dp_met: float = option(-2.0, ge=-20, le=20, unit="kPa", help="DIN 18008-1 Table 3")
    winter_dp_met: float = option(4.0, ge=-20, le=20, unit="kPa", help="DIN 18008-1 Table 3")
    site_altitude: float | None = option(None, ge=-500, le=9000, unit="m", help="null: DIN's +600 / -300 m")
    production_altitude: float | None = option(None, ge=-500, le=9000, unit="m", help="where the units are sealed")
    p_atm: float = option(100.0, gt=0, le=200, unit="kPa", help="air pressure of the cavity gas law")
    climate_psi0: float = option(0.6, ge=0, le=1.0, help="combination factor of the climatic loads")
    gamma_q: float = option(1.5, ge=1.0, le=3.0, help="partial factor of a leading climatic load")
    mesh: int = option(RINGS, ge=4, le=200, help="plate mesh: pieces per side of each fan triangle")

    def __post_init__(self) -> None:
        check_fields(self, "structure.glass")
        if (self.site_altitude is None) != (self.production_altitude is None):
            raise ConfigError(f"structure.glass.site_altitude = {self.site_altitude!r}, production_altitude = "
                              f"{self.production_altitude!r}: expected both or neither")

    def duration_h(self, kind: str) -> float:
        return float(getattr(self, f"duration_{kind}_h"))

    def altitude_change(self) -> tuple[float, float]:
        """``(summer, winter)`` dH = site - production altitude, m: DIN 18008-1's +600 / -300 m unless both
        altitudes are given."""
        if self.site_altitude is None:
            return 600.0, -300.0
        d = float(self.site_altitude - self.production_altitude)
        return d, d


# -- material and section ------------------------------------------------------------------------------
def kmod(hours):
    """Load duration factor ``0.663 t^(-1/16)`` (t in hours, EN 16612:2019), at most 1; float or array."""
    out = np.minimum(KMOD_MAX, 0.663 * np.asarray(hours, dtype=float) ** (-1.0 / 16.0))
    return float(out) if out.ndim == 0 else out


def design_strength(treatment: str, k_mod, options: GlassOptions, enamelled: bool = False):
    """f_g,d (MPa) of a ply (EN 16612:2019 eq. (5)); ``k_mod`` float or array."""
    f_b = (F_BK_ENAMEL if enamelled else F_BK)[treatment]
    annealed = options.k_e * k_mod * options.k_sp * F_GK / options.gamma_m_a
    return annealed + options.k_v * (f_b - F_GK) / options.gamma_m_v


def ply_thickness(nominal: float, mode: str = "nominal") -> float:
    """The thickness a calculation takes (mm): nominal, or nominal minus the EN 572-2 tolerance."""
    if mode == "nominal":
        return float(nominal)
    tol = next((t for top, t in THICKNESS_TOL if nominal <= top + 1e-9), THICKNESS_TOL[-1][1])
    return float(nominal - tol)


def laminate(plies_mm, interlayer_mm: float, omega: float) -> tuple[float, np.ndarray]:
    """``(h_ef,w, h_ef,sigma (n,))`` mm of a laminate of ``plies_mm (n,)`` with interlayers ``interlayer_mm``
    thick and shear transfer ``omega`` (EN 16612:2019 Annex D); one ply: its own thickness twice."""
    h = np.asarray(plies_mm, dtype=float)
    if len(h) == 1:
        return float(h[0]), h.copy()
    mid = np.cumsum(h) - 0.5 * h + interlayer_mm * np.arange(len(h))       # mid-planes from the top face
    hm = mid - (h * mid).sum() / h.sum()                                    # from the laminate's mid-plane
    hw3 = (h ** 3).sum() + 12.0 * omega * (h * hm ** 2).sum()
    return float(np.cbrt(hw3)), np.sqrt(hw3 / (h + 2.0 * omega * np.abs(hm)))


def plate_stiffness(h_mm) -> np.ndarray:
    """Bending stiffness D = E h^3 / (12 (1 - nu^2)), N mm."""
    return E_GLASS * np.asarray(h_mm, dtype=float) ** 3 / (12.0 * (1.0 - NU_GLASS ** 2))


@dataclass(frozen=True)
class PaneModel:
    """One pane of a unit as the check sees it: calculation thicknesses of its plies, interlayer, family,
    per ply treatment and enamel, weight per area (N/mm2 per kN/m3 of glass: ``glass_mm * 1e-6``, plus
    the interlayers at their density)."""

    name: str
    plies_mm: tuple[float, ...]
    interlayer: str
    interlayer_mm: float
    family: int
    treatment: tuple[str, ...]
    enamelled: tuple[bool, ...]
    glass_mm: float
    interlayer_total_mm: float

    def omega(self, kind: str, options: GlassOptions) -> float:
        if len(self.plies_mm) == 1:
            return 0.0
        return float(options.omega) if options.omega is not None else OMEGA[self.family][kind]

    def thickness(self, kind: str, options: GlassOptions) -> tuple[float, np.ndarray]:
        return laminate(self.plies_mm, self.interlayer_mm, self.omega(kind, options))

    def weight(self, glass_unit_weight: float) -> float:
        """Self-weight per area, N/mm2 (``glass_unit_weight`` kN/m3)."""
        from fabricate.cad.glass import INTERLAYER_DENSITY

        rho = INTERLAYER_DENSITY.get(self.interlayer, 1000.0)
        return glass_unit_weight * 1e-6 * self.glass_mm + rho * 9.81e-9 * self.interlayer_total_mm


def pane_models(build_up, options: GlassOptions) -> list[PaneModel]:
    """The panes of a :class:`fabricate.cad.glass.BuildUp`, outside in (one, or two for an insulated unit)."""
    plies = build_up.plies()
    panes = [("outer", build_up.outer)] + ([("inner", build_up.inner)] if build_up.inner is not None else [])
    out, k = [], 0
    for name, p in panes:
        mine = plies[k:k + len(p.plies_mm)]
        k += len(p.plies_mm)
        family = options.sgp_family if p.interlayer == "SGP" else options.pvb_family
        out.append(PaneModel(name if build_up.inner is not None else "pane",
                             tuple(ply_thickness(t, options.thickness) for t in p.plies_mm), p.interlayer,
                             float(p.interlayer_mm), family, tuple(p.treatment),
                             tuple(any(c == "enamel" for _, c in q.coatings) for q in mine),
                             float(sum(p.plies_mm)), float(p.interlayer_mm * (len(p.plies_mm) - 1))))
    return out


# -- insulating units ------------------------------------------------------------------------------------
def isochore_pressure(dt: float, dp_met: float, dh: float) -> float:
    """p0 = c1 dT - dp_met + c2 dH, kPa (DIN 18008-1 Annex A, EN 16612)."""
    return C1_KPA_K * dt - dp_met + C2_KPA_M * dh


def insulating_factor(volume_unit, area, cavity_mm: float, d_outer, d_inner, p_atm_kpa: float) -> np.ndarray:
    """phi = 1 / (1 + p_atm (v_o + v_i) / V): ``volume_unit`` the plate's unit volume (mm^6, per q / D),
    ``area`` mm2, the panes' stiffnesses ``d_outer``, ``d_inner`` N mm; p_atm kPa."""
    v = np.asarray(volume_unit) * (1.0 / np.asarray(d_outer) + 1.0 / np.asarray(d_inner))   # mm^3 per N/mm2
    return 1.0 / (1.0 + p_atm_kpa * 1e-3 * v / (np.asarray(area) * cavity_mm))


def share(w_outer, w_inner, p0, delta_outer, phi) -> tuple[np.ndarray, np.ndarray]:
    """``(q_outer, q_inner)``: the net load on each pane of an insulating unit (positive toward the
    beams, inward) under the external loads ``w_outer`` on the outer pane, ``w_inner`` on the inner one
    and the isochore pressure ``p0`` (cavity over-pressure), DIN 18008-1 Table A.2."""
    d_o = np.asarray(delta_outer)
    d_i = 1.0 - d_o
    q_o = (d_o + phi * d_i) * w_outer + (1.0 - phi) * d_o * w_inner - phi * p0
    q_i = (1.0 - phi) * d_i * w_outer + (d_i + phi * d_o) * w_inner + phi * p0
    return q_o, q_i


# -- panels ------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class GlassPanels:
    """The glass units to check.

    ids : (u,) str unit ids.  outlines : list of u ``(k, 2)`` float mm, each unit's outline in its plane.
    inward : (u, 3) float unit normal of the bearing face, toward the beams.
    label : (u,) int: units of one label share one outline (congruent): one plate solve per label.
    """

    ids: tuple[str, ...]
    outlines: tuple[np.ndarray, ...]
    inward: np.ndarray
    label: np.ndarray


def panels_from_parts(parts, tol: float = 1.0) -> GlassPanels:
    """The units of a :class:`fabricate.cad.parts.Parts`: the bearing ply's cut outline
    (``PartGroup.flat``), the outward normal of its bearing face, congruent outlines (within ``tol`` mm,
    mirror images too: :func:`fabricate.cad.congruence.ring_classes`) under one label."""
    from fabricate.cad.congruence import ring_classes
    from fabricate.cad.glass import bearing_groups
    from fabricate.cad.parts import unit_id

    ids, outlines, inward, labels, base = [], [], [], [], 0
    for g in bearing_groups(parts):  # one group per corner count
        if not len(g):
            continue
        c = ring_classes(g.flat[:, None], tol)
        ids += [unit_id(i) for i in g.ids]
        outlines += list(np.asarray(g.flat, dtype=float))
        inward.append(g.normals[:, g.outline_face])
        labels.append(c.label + base)
        base += c.count
    if not ids:
        return GlassPanels((), (), np.zeros((0, 3)), np.zeros(0, dtype=np.int64))
    return GlassPanels(tuple(ids), tuple(outlines), np.concatenate(inward), np.concatenate(labels))


def unit_responses(panels: GlassPanels, rings: int = RINGS) -> tuple[list[PlateResponse], np.ndarray]:
    """One plate solve per label: ``(responses (c,), index (u,))``, unit ``i`` reads ``responses[index[i]]``."""
    _, first, index = np.unique(panels.label, return_index=True, return_inverse=True)
    return [solve_plate(panels.outlines[int(f)], NU_GLASS, rings) for f in first], index.ravel()


# -- the check ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Combination:
    """One combination the glass is checked for: name, ``uls`` | ``sls``, factor per case."""

    name: str
    kind: str
    factors: dict


def glass_combinations(combinations, insulated: bool, options: GlassOptions) -> list[Combination]:
    """The structure's ``[(name, kind, factors)]`` with ``K_FI`` on the ULS ones; for an insulating unit
    each also with the summer and the winter climatic load (``psi_0 gamma_Q``, ``psi_0`` in SLS) and the
    climatic loads leading (``gamma_Q``, 1.0 in SLS) with the largest permanent factor of that kind."""
    kfi = K_FI[options.consequence_class]
    out = []
    for name, kind, f in combinations:
        f = {k: v * (kfi if kind == "uls" else 1.0) for k, v in f.items()}
        out.append(Combination(name, kind, f))
        if insulated:
            c = options.climate_psi0 * (options.gamma_q * kfi if kind == "uls" else 1.0)
            for season in ("summer", "winter"):
                out.append(Combination(f"{name} + {c:g}C {season}", kind, {**f, f"climate_{season}": c}))
    if insulated:
        for kind in ("uls", "sls"):
            perm = max((f.get("glass", 0.0) for _, k, f in combinations if k == kind), default=1.0)
            g = options.gamma_q * kfi if kind == "uls" else 1.0
            for season in ("summer", "winter"):
                out.append(Combination(f"{kind.upper()} {perm:g}G + {g:g}C {season}", kind,
                                       {"glass": perm * (kfi if kind == "uls" else 1.0), f"climate_{season}": g}))
    return out


@dataclass(frozen=True, eq=False)
class GlassCheck:
    """The glass check's results per unit (u,) and its facts.

    sigma_mpa : largest principal stress of any ply under the governing ULS combination.
    f_gd_mpa : that ply's design strength.  utilization_stress : sigma / f_g,d (largest over plies and
    combinations).  uls, ply : the governing combination and ``pane ply k``.  deflection_mm : largest
    pane deflection under the governing SLS combination; deflection_limit_mm; utilization_deflection.
    span_mm : twice the inradius.  tilt_deg : from the vertical.  phi : insulating unit factor (nan
    without a cavity).  notes : per unit (overhead rules).
    """

    ids: tuple[str, ...]
    build_up: str
    area_m2: np.ndarray
    span_mm: np.ndarray
    tilt_deg: np.ndarray
    overhead: np.ndarray
    sigma_mpa: np.ndarray
    f_gd_mpa: np.ndarray
    k_mod: np.ndarray
    utilization_stress: np.ndarray
    uls: tuple[str, ...]
    ply: tuple[str, ...]
    treatment: tuple[str, ...]
    deflection_mm: np.ndarray
    deflection_limit_mm: np.ndarray
    utilization_deflection: np.ndarray
    sls: tuple[str, ...]
    phi: np.ndarray
    notes: tuple[tuple[str, ...], ...]
    options: GlassOptions
    facts: dict = field(default_factory=dict)

    @property
    def utilization(self) -> np.ndarray:
        """(u,) the larger of the stress and the deflection utilization."""
        return np.maximum(self.utilization_stress, self.utilization_deflection)

    def report(self) -> dict:
        """report.json's ``glass``: what was checked, the worst unit, counts over 1."""
        u = self.utilization
        out = {"standard": "EN 16612:2019 (laminated: Annex D; insulating units and overhead glazing: DIN 18008-1/-2)",
               "build_up": self.build_up, "units": len(self.ids), "check": self.options.check,
               "consequence_class": self.options.consequence_class,
               "max_utilization": float(u.max()) if len(u) else 0.0,
               "max_utilization_stress": float(self.utilization_stress.max()) if len(u) else 0.0,
               "max_utilization_deflection": float(self.utilization_deflection.max()) if len(u) else 0.0,
               "over_1": int((u > 1.0).sum()), "overhead_units": int(self.overhead.sum()), **self.facts}
        if len(u):
            i = int(np.argmax(u))
            what = "stress" if self.utilization_stress[i] >= self.utilization_deflection[i] else "deflection"
            out["worst"] = {"id": self.ids[i], "governs": what, "utilization": float(u[i]),
                            "sigma_mpa": float(self.sigma_mpa[i]), "f_gd_mpa": float(self.f_gd_mpa[i]),
                            "uls": self.uls[i], "ply": self.ply[i], "treatment": self.treatment[i],
                            "deflection_mm": float(self.deflection_mm[i]),
                            "deflection_limit_mm": float(self.deflection_limit_mm[i]), "sls": self.sls[i],
                            "span_mm": float(self.span_mm[i]), "notes": list(self.notes[i])}
        notes = sorted({n for ns in self.notes for n in ns})
        if notes:
            out["notes"] = notes
        return out

    def per_unit(self) -> dict[str, dict]:
        """``{unit id: {...}}``: the figures a glass schedule row or an IFC property set takes."""
        return {pid: {"utilization": float(self.utilization[i]),
                      "utilization_stress": float(self.utilization_stress[i]),
                      "utilization_deflection": float(self.utilization_deflection[i]),
                      "sigma_mpa": float(self.sigma_mpa[i]), "f_gd_mpa": float(self.f_gd_mpa[i]),
                      "deflection_mm": float(self.deflection_mm[i]),
                      "deflection_limit_mm": float(self.deflection_limit_mm[i]),
                      "governing": self.uls[i] if self.utilization_stress[i] >= self.utilization_deflection[i]
                      else self.sls[i]}
                for i, pid in enumerate(self.ids)}

    def measures(self) -> dict[str, dict]:
        """``{name: entry}`` for the run's measures (:func:`fabricate.report.measures.entry`), units by
        their mesh face (``P0001``: face 0); enforced when ``check`` is ``enforce``."""
        from fabricate.report.measures import entry

        enforced = self.options.check == "enforce"
        faces = np.array([int(i.lstrip("P")) - 1 for i in self.ids], dtype=np.int64)   # P0001 -> face 0
        return {"glass_stress": entry(self.utilization_stress, 1.0, "ratio", "panel", ids=faces, enforced=enforced,
                                      extra={"mpa": self.sigma_mpa},
                                      what="glass stress / f_g,d (EN 16612, governing ULS combination)"),
                "glass_deflection": entry(self.utilization_deflection, 1.0, "ratio", "panel", ids=faces,
                                          enforced=enforced, extra={"mm": self.deflection_mm},
                                          what=f"glass deflection / (span/{self.options.deflection_limit:g}) (SLS)")}


def check_glass(panels: GlassPanels, build_up, loads, combinations, options: GlassOptions | None = None,
                up=(0.0, 0.0, 1.0)) -> GlassCheck:
    """Check every unit of ``panels`` built as ``build_up`` (:class:`fabricate.cad.glass.BuildUp`).

    loads : the structure's characteristic loads (``glass_unit_weight`` kN/m3, ``snow``,
        ``wind_pressure``, ``wind_suction`` kN/m2: :class:`fabricate.structure.options.LoadsOptions`).
    combinations : ``[(name, "uls" | "sls", {case: factor})]`` (``StructureOptions.combination_list()``).
    up : the up direction of the loads.
    """
    from fabricate.cad.glass import OVERHEAD_DEG

    t0 = time.perf_counter()
    opt = options or GlassOptions()
    u = len(panels.ids)
    upv = np.asarray(up, dtype=float) / np.linalg.norm(up)
    panes = pane_models(build_up, opt)
    insulated = len(panes) == 2
    responses, index = unit_responses(panels, opt.mesh)
    R = {k: np.array([getattr(r, k) for r in responses])[index] if u else np.zeros(0)
         for k in ("w_max", "m_max", "volume", "area", "inradius")}
    n_in = np.asarray(panels.inward, dtype=float).reshape(-1, 3)
    down = n_in @ -upv                                             # cos of the slope, + when beams are below
    tilt = np.degrees(np.arcsin(np.clip(np.abs(down), 0.0, 1.0)))
    kpa = 1e-3                                                     # kN/m2 -> N/mm2
    # characteristic external load per case on each pane (u,), + toward the beams
    zero = np.zeros(u)
    ext = {p.name: {} for p in panes}
    for p in panes:
        ext[p.name]["glass"] = p.weight(loads.glass_unit_weight) * down
    top = panes[0].name
    ext[top]["snow"] = loads.snow * kpa * np.where(down > 0, down ** 2, 0.0)
    ext[top]["wind_pressure"] = np.full(u, loads.wind_pressure * kpa)
    ext[top]["wind_suction"] = np.full(u, -loads.wind_suction * kpa)
    dh_s, dh_w = opt.altitude_change()
    p0 = {"climate_summer": isochore_pressure(opt.summer_dt, opt.summer_dp_met, dh_s),
          "climate_winter": isochore_pressure(opt.winter_dt, opt.winter_dp_met, dh_w)}
    combos = glass_combinations(combinations, insulated, opt)
    cases = sorted({c for cb in combos for c in cb.factors})
    skipped = sorted(c for c in cases if c not in ON_GLASS and c not in p0)
    # per case: net load, deflection and ply stresses of each pane (u,)
    w_case, s_case, phi_of, present = {}, {}, {}, {}
    for case in cases:
        if case in skipped:
            continue
        kind = CASE_DURATION.get(case, "permanent")
        h = [p.thickness(kind, opt) for p in panes]
        D = [plate_stiffness(hw) for hw, _ in h]
        if insulated:
            phi = insulating_factor(R["volume"], R["area"], build_up.cavity_mm, D[0], D[1], opt.p_atm)
            phi_of[kind] = phi
            q = share(ext[panes[0].name].get(case, zero), ext[panes[1].name].get(case, zero),
                      p0.get(case, 0.0) * kpa, D[0] / (D[0] + D[1]), phi)
        else:
            q = (ext[panes[0].name].get(case, zero),)
        loaded = [ext[p.name].get(case, zero) != 0 for p in panes]
        present[case] = np.logical_or.reduce(loaded) | (p0.get(case, 0.0) != 0)
        for j, p in enumerate(panes):
            w_case[case, p.name] = q[j] * R["w_max"] / D[j]
            for k, hs in enumerate(h[j][1]):
                s_case[case, p.name, k] = 6.0 * q[j] * R["m_max"] / hs ** 2
    # combinations
    sig, fgd, km, util_s = np.zeros(u), np.full(u, np.nan), np.full(u, np.nan), np.full(u, -1.0)
    uls, ply, treat = [""] * u, [""] * u, [""] * u
    defl, util_d, sls = np.zeros(u), np.full(u, -1.0), [""] * u
    span = 2.0 * R["inradius"]
    limit = span / opt.deflection_limit
    for cb in combos:
        active = {c: f for c, f in cb.factors.items() if f and c not in skipped}
        if cb.kind == "sls":
            for p in panes:
                w = np.abs(sum(f * w_case[c, p.name] for c, f in active.items()) + zero)
                r = w / limit
                better = r > util_d
                util_d = np.where(better, r, util_d)
                defl = np.where(better, w, defl)
                for i in np.flatnonzero(better).tolist():  # names of the units this combination governs
                    sls[i] = cb.name
            continue
        hours = np.full(u, opt.duration_permanent_h)     # the shortest load acting on each unit (DIN 18008-1 8.3.7)
        for c in active:
            hours = np.where(present[c], np.minimum(hours, opt.duration_h(CASE_DURATION.get(c, "permanent"))), hours)
        k_mod = kmod(hours)
        for p in panes:
            for k, t in enumerate(p.treatment):
                s = np.abs(sum(f * s_case[c, p.name, k] for c, f in active.items()) + zero)
                f_d = design_strength(t, k_mod, opt, p.enamelled[k])
                r = s / f_d
                better = r > util_s
                util_s, sig = np.where(better, r, util_s), np.where(better, s, sig)
                fgd, km = np.where(better, f_d, fgd), np.where(better, k_mod, km)
                where = f"{p.name} ply {k + 1}" if len(p.plies_mm) > 1 else p.name
                for i in np.flatnonzero(better).tolist():  # names of the units this combination governs
                    uls[i], ply[i], treat[i] = cb.name, where, t
    overhead = tilt > OVERHEAD_DEG
    notes = _overhead_notes(build_up)
    phi = phi_of.get("wind", phi_of.get("permanent", np.full(u, np.nan))) if insulated else np.full(u, np.nan)
    facts = {"load_cases": [c for c in cases if c not in skipped], "not_on_glass": skipped,
             "combinations": len(combos), "plate_solves": len(responses), "mesh": opt.mesh,
             "k_mod": {k: round(float(kmod(opt.duration_h(k))), 3) for k in ("permanent", "snow", "climate", "wind")},
             "panes": [{"pane": p.name, "plies_mm": list(p.plies_mm), "treatment": list(p.treatment),
                        "interlayer": p.interlayer if len(p.plies_mm) > 1 else "",
                        "family": p.family if len(p.plies_mm) > 1 else None,
                        "h_ef_w_mm": {k: round(p.thickness(k, opt)[0], 3) for k in ("wind", "snow", "permanent")}}
                       for p in panes],
             "seconds": round(time.perf_counter() - t0, 3)}
    if insulated:
        facts["climate"] = {"p0_summer_kpa": round(p0["climate_summer"], 3),
                            "p0_winter_kpa": round(p0["climate_winter"], 3),
                            "phi_min": float(np.nanmin(phi)) if u else None,
                            "phi_max": float(np.nanmax(phi)) if u else None, "note": CLIMATE_NOTE}
    return GlassCheck(ids=tuple(panels.ids), build_up=build_up.short(), area_m2=R["area"] * 1e-6, span_mm=span,
                      tilt_deg=tilt, overhead=overhead, sigma_mpa=sig, f_gd_mpa=fgd, k_mod=km,
                      utilization_stress=np.maximum(util_s, 0.0), uls=tuple(uls), ply=tuple(ply),
                      treatment=tuple(treat), deflection_mm=defl, deflection_limit_mm=limit,
                      utilization_deflection=np.maximum(util_d, 0.0), sls=tuple(sls), phi=phi,
                      notes=tuple(notes if o else () for o in overhead.tolist()), options=opt, facts=facts)


def _overhead_notes(build_up) -> tuple[str, ...]:
    """What an overhead unit of ``build_up`` is told: the build-up's warnings, the PVB rule, and the
    post-breakage note (the residual capacity of the broken lower pane is not computed here)."""
    out = list(build_up.overhead_warnings())
    low = build_up.lower_pane()
    if low.laminated and low.interlayer == "PVB" and low.interlayer_mm < OVERHEAD_PVB_MM - 1e-9:
        out.append(f"the lower pane's PVB is {low.interlayer_mm:g} mm: DIN 18008-2 asks at least "
                   f"{OVERHEAD_PVB_MM:g} mm over people")
    if low.laminated:
        out.append("post-breakage: the laminated lower pane must hold when broken (DIN 18008-2: residual "
                   "capacity by its rules or by test); not computed here")
    return tuple(out)


def check_parts(parts, structure, options: GlassOptions | None = None) -> GlassCheck:
    """:func:`check_glass` for the glass units of ``parts`` under the loads and combinations of the
    :class:`fabricate.structure.options.StructureOptions` ``structure``."""
    return check_glass(panels_from_parts(parts), parts.spec.glass, structure.loads, structure.combination_list(),
                       options, up=structure.up)


# -- outputs -------------------------------------------------------------------------------------------------
GLASS_CHECK_COLUMNS = ("id", "build_up", "area_m2", "span_mm", "tilt_deg", "overhead", "utilization",
                       "sigma_mpa", "f_gd_mpa", "k_mod", "utilization_stress", "uls", "ply", "treatment",
                       "deflection_mm", "deflection_limit_mm", "utilization_deflection", "sls", "phi", "notes")


def write_glass_check(check: GlassCheck, path) -> dict:
    """Write ``glass_check.csv`` (atomic): one row per glass unit.  Returns ``file, bytes, rows, seconds``."""
    from optimize.atomic import atomic_open
    from optimize.errors import write_error

    t0 = time.perf_counter()
    path = Path(path)
    u = check.utilization

    def num(x, fmt):
        return "" if not math.isfinite(float(x)) else fmt.format(float(x))

    try:
        with atomic_open(path, "w", encoding="utf-8", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(GLASS_CHECK_COLUMNS)
            for i, pid in enumerate(check.ids):  # one row per unit
                w.writerow((pid, check.build_up, num(check.area_m2[i], "{:.4f}"), num(check.span_mm[i], "{:.1f}"),
                            num(check.tilt_deg[i], "{:.1f}"), "yes" if check.overhead[i] else "no",
                            num(u[i], "{:.4f}"), num(check.sigma_mpa[i], "{:.2f}"), num(check.f_gd_mpa[i], "{:.2f}"),
                            num(check.k_mod[i], "{:.3f}"), num(check.utilization_stress[i], "{:.4f}"), check.uls[i],
                            check.ply[i], check.treatment[i], num(check.deflection_mm[i], "{:.2f}"),
                            num(check.deflection_limit_mm[i], "{:.2f}"),
                            num(check.utilization_deflection[i], "{:.4f}"), check.sls[i],
                            num(check.phi[i], "{:.4f}"), "; ".join(check.notes[i])))
    except OSError as exc:
        raise write_error(path, "glass check", exc) from exc
    return {"file": path.name, "bytes": path.stat().st_size, "rows": len(check.ids),
            "seconds": time.perf_counter() - t0}
