"""The structure stage's options: the frame, its loads and the check, as frozen objects (one place
for every default, bound and help; the ``structure`` config section is derived from them in
:mod:`fabricate.app.config_structure`).

Units: section dimensions and lengths in mm, area loads in kN/m2, unit weights in kN/m3,
moduli in MPa (N/mm2).  Load case names follow EN 1991 (self-weight and permanent loads
1991-1-1, snow 1991-1-3, wind 1991-1-4); the default combinations are EN 1990 eq. 6.10 with
the recommended factors (gamma_G 1.35 / 1.0, gamma_Q 1.5, psi_0 snow 0.5, wind 0.6) and the
characteristic ones for the deflections.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ..fields import check_fields, option
from .sections import SectionProperties, section
from .glass import GlassOptions

CASES = ("self_weight", "hubs", "glass", "finishes", "snow", "wind_pressure", "wind_suction", "maintenance",
         "temperature_rise", "temperature_fall")
"""The basic load cases (EN 1991-style names); permanent: self_weight, hubs, glass, finishes."""
KFI = {"CC1": 0.9, "CC2": 1.0, "CC3": 1.1}
"""EN 1990 Annex B Table B3: the factor K_FI on the partial factors of the unfavourable actions."""
ALPHA = {"a0": 0.13, "a": 0.21, "b": 0.34, "c": 0.49, "d": 0.76}
"""Imperfection factor of each flexural buckling curve (EN 1993-1-1 Table 6.1)."""
GRADES = {"S235": 235.0, "S275": 275.0, "S355": 355.0, "S460": 460.0}
"""Yield strength f_y (MPa) of the structural steel grades (EN 10025-2, t <= 40 mm)."""


@dataclass(frozen=True, kw_only=True)
class SectionOptions:
    """A beam section (mm): ``plate`` width x depth, ``rhs`` depth x width x web (wall),
    ``tee`` / ``i`` depth x width (flange) x web x flange thickness."""

    shape: Literal["plate", "rhs", "tee", "i"] = option("plate")
    depth: float = option(gt=0, unit="mm")
    width: float = option(gt=0, unit="mm")
    web: float | None = option(None, gt=0, unit="mm")
    flange: float | None = option(None, gt=0, unit="mm")

    def properties(self, key: str = "section") -> SectionProperties:
        return section(self.shape, depth=self.depth, width=self.width, web=self.web, flange=self.flange, key=key)


@dataclass(frozen=True)
class LoadsOptions:
    """Characteristic loads: unit weights kN/m3, area loads kN/m2 (>= 0; wind signs are in the case)."""

    steel_unit_weight: float = option(78.5, gt=0, unit="kN/m3", help="EN 1991-1-1 Table A.4")
    glass_unit_weight: float = option(25.0, gt=0, unit="kN/m3", help="EN 1991-1-1 Table A.4 (glass in sheets)")
    finishes: float = option(0.0, ge=0, unit="kN/m2", help="permanent, per m2 of glass (fixings, gaskets)")
    snow: float = option(0.8, ge=0, unit="kN/m2", help="s = mu_i C_e C_t s_k, per m2 of plan")
    wind_pressure: float = option(0.5, ge=0, unit="kN/m2", help="w_e toward the structure, normal to the panels")
    wind_suction: float = option(0.5, ge=0, unit="kN/m2", help="w_e away from the structure (uplift)")
    maintenance: float = option(0.4, ge=0, unit="kN/m2",
                                help="EN 1991-1-1 Table 6.10, roofs of category H: q_k per m2 of plan (0.4 recommended)")
    temperature: float = option(30.0, ge=0, unit="K",
                                help="uniform temperature change +/- dT of the steel from its erection temperature "
                                     "(EN 1991-1-5 6.1.3)")

    def __post_init__(self) -> None:
        check_fields(self, "structure.loads")


@dataclass(frozen=True)
class CombinationOptions:
    """One combination: ``name``, ``kind`` (``uls`` strength, ``sls`` deflection), factors per case
    (a partial factor times a combination factor, >= 0)."""

    name: str = option(min_length=1, max_length=60)
    kind: Literal["uls", "sls"]
    factors: dict[Literal["self_weight", "hubs", "glass", "finishes", "snow", "wind_pressure", "wind_suction",
                          "maintenance", "temperature_rise", "temperature_fall"], float]


def _perm(g: float) -> dict[str, float]:
    return {"self_weight": g, "hubs": g, "glass": g, "finishes": g}


PSI0 = {"snow": 0.5, "wind": 0.6, "temperature": 0.6, "maintenance": 0.0}
"""EN 1990 Table A1.1: psi_0 of snow (sites below 1000 m), wind, temperature, roofs of category H."""


def default_combinations(kfi: float = 1.0, maintenance: bool = True, temperature: bool = True) -> tuple:
    """EN 1990 eq. 6.10 with the recommended factors (gamma_G 1.35 K_FI unfavourable, 1.0 favourable,
    gamma_Q 1.5 K_FI, :data:`PSI0`), each variable action leading in turn: snow, wind (pressure; suction
    with the permanent actions favourable), temperature (rise and fall, snow and wind accompanying),
    maintenance alone (EN 1991-1-1 3.3.2(1): not with snow or wind); temperature does not accompany the
    snow- and wind-led ones.  SLS: the characteristic combinations of the same."""
    g, q = 1.35 * kfi, 1.5 * kfi
    f = lambda x: round(x, 4)  # noqa: E731
    s0, w0 = PSI0["snow"], PSI0["wind"]
    out = [(f"ULS {f(g):g}G", "uls", _perm(f(g))),
           (f"ULS {f(g):g}G + {f(q):g}S + {f(q * w0):g}W", "uls", dict(_perm(f(g)), snow=f(q), wind_pressure=f(q * w0))),
           (f"ULS {f(g):g}G + {f(q):g}W + {f(q * s0):g}S", "uls", dict(_perm(f(g)), wind_pressure=f(q), snow=f(q * s0))),
           (f"ULS 1.0G + {f(q):g}W uplift", "uls", dict(_perm(1.0), wind_suction=f(q)))]
    if temperature:
        for sign in ("rise", "fall"):
            out.append((f"ULS {f(g):g}G + {f(q):g}T {sign} + {f(q * s0):g}S + {f(q * w0):g}W", "uls",
                        dict(_perm(f(g)), **{f"temperature_{sign}": f(q)}, snow=f(q * s0), wind_pressure=f(q * w0))))
    if maintenance:
        out.append((f"ULS {f(g):g}G + {f(q):g}H maintenance", "uls", dict(_perm(f(g)), maintenance=f(q))))
    out += [("SLS G + S + 0.6W", "sls", dict(_perm(1.0), snow=1.0, wind_pressure=w0)),
            ("SLS G + W + 0.5S", "sls", dict(_perm(1.0), wind_pressure=1.0, snow=s0)),
            ("SLS G + W uplift", "sls", dict(_perm(1.0), wind_suction=1.0))]
    if maintenance:
        out.append(("SLS G + H maintenance", "sls", dict(_perm(1.0), maintenance=1.0)))
    return tuple(out)


DEFAULT_COMBINATIONS = default_combinations()
"""The default combinations in consequence class CC2 with every action present."""


@dataclass(frozen=True)
class SizingOptions:
    """``fabricate size``: candidate sections (lightest passing one per group) and the grouping."""

    sections: tuple[SectionOptions, ...] = option(())
    group_by: Literal["all", "boundary"] = option("boundary", help="all beams together, or boundary and inner apart")
    max_rounds: int = option(6, ge=1, le=50)

    def __post_init__(self) -> None:
        check_fields(self, "structure.sizing")


@dataclass(frozen=True)
class StructureOptions:
    """The ``structure`` section: the check's keys and its nested options (``section`` null: the
    section the parts are welded from, ``parts.beam``; ``combinations`` null: :data:`DEFAULT_COMBINATIONS`)."""

    check: Literal["off", "report", "enforce"] = option("off", help="off skips the check; enforce fails the run")
    grade: Literal["S235", "S275", "S355", "S460"] = option("S355", help="steel grade (EN 10025-2)")
    gamma_m0: float = option(1.0, ge=1.0, le=2.0, help="partial factor of the cross-section resistance")
    buckling_curve: Literal["a0", "a", "b", "c", "d"] = option(
        "c", help="EN 1993-1-1 Table 6.1 (c: tees, plates, cold-formed RHS)")
    buckling_length_factor: float = option(1.0, gt=0, le=10.0, help="buckling length / beam length")
    elastic_modulus: float = option(210000.0, gt=0, le=1e6, unit="MPa")
    shear_modulus: float = option(81000.0, gt=0, le=1e6, unit="MPa")
    section: SectionOptions | None = None
    connections: Literal["rigid", "pinned"] = option("rigid")
    supports: Literal["lowest", "boundary", "outline"] | tuple[int, ...] = option(
        "lowest", help="the supported nodes: a rule or vertex indices")
    support_tolerance: float | None = option(None, ge=0, le=1e6, unit="mm",
                                             help="above the lowest ('lowest'); null: 5% of the height")
    support_kind: Literal["pinned", "fixed"] = option("pinned")
    up: tuple[float, float, float] = option((0.0, 0.0, 1.0), help="the up direction of the loads")
    deflection_limit: float = option(200.0, gt=0, le=10000.0, help="span / n, beams and whole structure")
    span: float | None = option(None, gt=0, le=1e7, unit="mm", help="null: the shorter side of the plan")
    stability: Literal["off", "auto", "always"] = option(
        "auto", help="alpha_cr of every ULS combination (linear buckling analysis); second-order analysis with "
                     "the first-mode imperfection where alpha_cr < 10 (auto) or always")
    imperfection: float = option(300.0, ge=10.0, le=10000.0,
                                 help="n of the imperfection amplitude span / n along the first buckling mode")
    buckling_modes: int = option(3, ge=1, le=20, help="buckling modes computed and reported per combination")
    consequence_class: Literal["CC1", "CC2", "CC3"] = option(
        "CC2", help="EN 1990 Annex B: K_FI 0.9 / 1.0 / 1.1 on the unfavourable actions of the default combinations")
    loads: LoadsOptions = LoadsOptions()
    combinations: tuple[CombinationOptions, ...] | None = None
    sizing: SizingOptions = SizingOptions()
    glass: GlassOptions = GlassOptions()

    def __post_init__(self) -> None:
        check_fields(self, "structure")

    @property
    def fy(self) -> float:
        """Design yield strength f_y / gamma_M0 (MPa)."""
        return GRADES[self.grade] / self.gamma_m0

    def combination_list(self) -> list[tuple[str, str, dict[str, float]]]:
        """``[(name, kind, {case: factor})]``: the configured combinations or the EN 1990 defaults."""
        if self.combinations is None:
            return [(n, k, dict(f)) for n, k, f in default_combinations(
                KFI[self.consequence_class], self.loads.maintenance > 0, self.loads.temperature > 0)]
        return [(c.name, c.kind, dict(c.factors)) for c in self.combinations]


