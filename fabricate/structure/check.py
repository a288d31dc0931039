"""The structural check of a run: frame + loads -> OpenSees -> per beam results -> report.

``check_structure(structure, options, spec)`` is the one entry point (the pipeline stage,
``fabricate size`` and the benchmark call it): a pure function of the offset structure, the
``structure`` config section and the part spec.
"""
from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field

import numpy as np

from .engine import MechanismError, solve, solve_second_order
from .frame import Frame, frame_from_offset
from .loads import basic_cases, combine
from .options import ALPHA, GRADES
from .results import N_WORST, Results, evaluate, worst
from .sections import SectionProperties, built_section
from .stability import ALPHA_CR_LIMIT, Assembly, Buckling, imperfection

UTILIZATION_NOTE = ("max of the elastic cross-section check |N|/Npl + |My|/Mel,y + |Mz|/Mel,z (EN 1993-1-1 "
                    "6.2.1(7)) and the same with the compression over chi Npl (flexural buckling 6.3.1, "
                    "interaction factors 1); shear, torsion, lateral-torsional buckling and connections "
                    "are not checked")
CLASS_NOTE = ("section class of EN 1993-1-1 Table 5.2 at every point of the ULS combinations from the beam's N and "
              "strong-axis moment (webs internal parts, alpha plastic and psi elastic; tee stems and I flanges "
              "outstands, k_sigma of EN 1993-1-5 Table 4.2; flanges as uniformly compressed wherever N + M, the "
              "weak-axis moment included, compress them); class 4 fails: local buckling is not checked")


@dataclass(frozen=True, eq=False)
class StructureCheck:
    """A solved frame: ``frame``, ``cases`` (basic load cases), ``solution``, ``results``,
    ``supports`` (k,) vertex indices, ``section`` (the configured one), ``seconds`` per step."""

    frame: Frame
    cases: dict
    solution: object
    results: Results
    supports: np.ndarray
    section: SectionProperties
    options: object
    seconds: dict = field(default_factory=dict)
    stability: "Stability | None" = None

    @property
    def max_utilization(self) -> float:
        return float(self.results.utilization.max(initial=0.0))

    def deflection_ratio(self) -> np.ndarray:
        """(e,) float beam deflection / its limit."""
        return self.results.deflection_mm / self.results.deflection_limit_mm

    def slender(self) -> np.ndarray:
        """(k,) int the beams whose section is class 4 under their forces (local buckling is not
        checked: they fail)."""
        return np.nonzero(self.results.section_class.cls == 4)[0]

    def passes(self) -> bool:
        r = self.results
        stable = self.stability is None or self.stability.alpha_cr > 1.0
        return bool(self.max_utilization <= 1.0 and (self.deflection_ratio() <= 1.0).all() and stable
                    and r.displacement_mm.max(initial=0.0) <= r.displacement_limit_mm and not self.slender().size)


@dataclass(frozen=True, eq=False)
class Stability:
    """The linear buckling analysis of every ULS combination and the second-order analyses it asked for.

    alphas : {combination: alpha_cr}; buckling : the Buckling (modes) of the lowest one, ``combination``
    its name; second_order : {combination: how it was analysed: "P-Delta" or "amplified 1/(1 - 1/alpha_cr)"};
    imperfection_mm : the amplitude of the first-mode imperfection; first_order_utilization : max
    utilization before the second-order results replaced the first-order ones; lower_bounds : the
    combinations whose alpha_cr is the compression-only lower bound (:meth:`Assembly.buckling`); geometry :
    {combination: (n, 3) float} the imperfect node positions of those solved P-Delta (the model export).
    """

    alphas: dict
    buckling: Buckling | None
    combination: str
    second_order: dict
    imperfection_mm: float
    first_order_utilization: float
    seconds: float = 0.0
    lower_bounds: tuple = ()
    geometry: dict = field(default_factory=dict)

    @property
    def alpha_cr(self) -> float:
        return min(self.alphas.values(), default=float("inf"))


def configured_section(options, spec, structure) -> SectionProperties:
    """``structure.section`` or, when null, the section the parts are welded from (``parts.beam``: the
    plate, tee, I or RHS of the layer span's depth, :func:`built_section`)."""
    if options.section is not None:
        return options.section.properties("structure.section")
    d0, d1 = structure.beam_span
    return built_section(spec, abs(d1 - d0))


def default_span(V: np.ndarray, up) -> float:
    """The shorter side (mm) of the plan bounding box (the plane normal to ``up``)."""
    u = np.asarray(up, dtype=float) / np.linalg.norm(up)
    a = np.cross(u, [1.0, 0.0, 0.0] if abs(u[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(u, a)
    P = V @ np.stack([a, b], axis=1)
    ext = P.max(axis=0) - P.min(axis=0)
    return float(max(ext.min(), 1e-9))


def build(structure, options, spec, section: SectionProperties | None = None, parts=None):
    """``(frame, supports, cases)`` for a structure with one section everywhere (``parts``: the CAD
    stage's, for the hubs' weight)."""
    section = section or configured_section(options, spec, structure)
    frame, supports = frame_from_offset(
        structure, section, E=options.elastic_modulus, G=options.shear_modulus, supports=options.supports,
        support_tolerance=options.support_tolerance, support_kind=options.support_kind,
        pinned=options.connections == "pinned", up=options.up)
    cases = basic_cases(structure, frame, options.loads, spec.glass_thickness, options.up, parts)
    return frame, supports, cases


def solve_frame(frame, cases, options, structure) -> tuple:
    """``(solution, results, stability)`` of ``frame`` under ``cases`` with the config's combinations;
    where ``structure.stability`` asks for it, the ULS combinations with alpha_cr < 10 (or all) are
    solved second order and their results replace the first-order ones."""
    try:
        solution = solve(frame, cases)
    except MechanismError as exc:
        raise MechanismError(f"structure.supports = {options.supports!r} ({int(frame.supported().sum())} "
                             f"{options.support_kind} supports), structure.connections = {options.connections!r}: "
                             f"{exc}") from None
    span = options.span or default_span(np.asarray(structure.mesh.V), options.up)
    combos = options.combination_list()

    def run(sol, combinations):
        return evaluate(frame, cases, sol, combinations, fy=options.fy, deflection_limit=options.deflection_limit,
                        span_mm=span, alpha=ALPHA[options.buckling_curve],
                        buckling_length_factor=options.buckling_length_factor, fy_class=GRADES[options.grade])

    results = run(solution, combos)
    stab = None
    if options.stability != "off" and any(k == "uls" for _, k, _ in combos):
        stab, solution2, combos2 = second_order(frame, cases, solution, combos, options, span,
                                                float(results.utilization.max(initial=0.0)))
        if stab.second_order:
            results = run(solution2, combos2)
            solution = solution2
    return solution, results, stab


def mix(store: dict, factors: dict) -> np.ndarray:
    return sum(f * store[k] for k, f in factors.items())


SECOND = " | second order"
"""Suffix of the solution entries that hold a combination's second-order results."""


def second_order(frame, cases, solution, combos, options, span: float, u_first: float):
    """The buckling analysis of every ULS combination (:mod:`fabricate.structure.stability`) and the
    second-order (P-Delta) solution of those with alpha_cr < :data:`ALPHA_CR_LIMIT` (``auto``) or all
    (``always``) on the frame displaced along the combination's first mode by span / ``imperfection``
    (EN 1993-1-1 5.3.2(11)); a P-Delta solution that does not converge is replaced by the first-order
    forces amplified by ``1 / (1 - 1 / alpha_cr)`` (5.2.2(5)B), and nothing when alpha_cr <= 1 (unstable:
    the check fails).  Returns ``(Stability, solution, combinations)``: the combinations solved second
    order point at their own entries of the solution (factor 1)."""
    t0 = time.perf_counter()
    asm = Assembly(frame)
    import scipy.sparse.linalg as spla

    lu = spla.splu(asm.Ke) if len(asm.free) > 600 else None
    alphas, worst, worst_name = {}, None, ""
    modes, bounds = {}, []
    for name, kind, factors in combos:
        if kind != "uls":
            continue
        N = asm.axial(mix(solution.end_forces, factors), mix(solution.line_local, factors))
        b = asm.buckling(N, options.buckling_modes, lu=lu)
        alphas[name] = b.alpha_cr
        modes[name] = b
        if b.lower_bound:
            bounds.append(name)
        if worst is None or b.alpha_cr < worst.alpha_cr:
            worst, worst_name = b, name
    amp = span / options.imperfection
    ends, disp, reac, line = (dict(d) for d in (solution.end_forces, solution.displacements, solution.reactions,
                                                 solution.line_local))
    out, done, geometry = [], {}, {}
    for name, kind, factors in combos:
        a = alphas.get(name, float("inf"))
        wanted = kind == "uls" and (options.stability == "always" or a < ALPHA_CR_LIMIT) and len(modes[name].alphas)
        if not wanted or a <= 1.0:
            out.append((name, kind, factors))
            continue
        direction = mix(solution.displacements, factors)[:, :3]
        X = imperfection(frame, modes[name].modes[0], amp, direction)
        got = solve_second_order(frame, combine(cases, factors, name), X)
        key = name + SECOND
        if got is None:
            f = 1.0 / (1.0 - 1.0 / a)
            ends[key], disp[key] = f * mix(solution.end_forces, factors), f * mix(solution.displacements, factors)
            reac[key], line[key] = f * mix(solution.reactions, factors), mix(solution.line_local, factors)
            done[name] = f"amplified 1/(1 - 1/alpha_cr) = {f:.3g} (P-Delta did not converge)"
        else:
            ends[key], disp[key], reac[key], line[key] = got
            done[name] = "P-Delta"
            geometry[name] = X
        out.append((name, kind, {key: 1.0}))
    sol = dataclasses.replace(solution, end_forces=ends, displacements=disp, reactions=reac, line_local=line)
    stab = Stability(alphas, worst, worst_name, done, amp, u_first, round(time.perf_counter() - t0, 4), tuple(bounds),
                     geometry)
    return stab, sol, out


def check_structure(structure, options, spec, *, section_of=None, sections=None, parts=None) -> StructureCheck:
    """Build, load, solve and evaluate the beam frame of ``structure`` (an OffsetStructure).

    options : the :class:`~fabricate.structure.options.StructureOptions` (``cfg.structure.to_options()``);
    spec : the PartSpec (glass thickness, beam width).
    section_of, sections : optional per beam sections (sizing); default the configured one.
    parts : the CAD stage's Parts (the node parts' weight, load case ``hubs``), or None (no hubs).
    """
    t0 = time.perf_counter()
    section = configured_section(options, spec, structure)
    frame, supports, cases = build(structure, options, spec, section, parts)
    if sections is not None:
        frame = frame.with_sections(sections, section_of)
        cases = basic_cases(structure, frame, options.loads, spec.glass_thickness, options.up, parts)
    t1 = time.perf_counter()
    solution, results, stab = solve_frame(frame, cases, options, structure)
    t2 = time.perf_counter()
    seconds = {"model": round(t1 - t0, 4), "solve": round(t2 - t1 - solution.seconds.get("ours", 0.0), 4)}
    seconds.update({f"opensees_{k}": v for k, v in solution.seconds.items() if k not in ("opensees", "ours")})
    seconds["opensees"] = solution.seconds.get("opensees", 0.0)
    seconds["total"] = round(time.perf_counter() - t0, 4)
    seconds["ours"] = round(seconds["total"] - seconds["opensees"], 4)
    if stab is not None:
        seconds["stability"] = stab.seconds
    return StructureCheck(frame, cases, solution, results, supports, section, options, seconds, stab)


def report(check: StructureCheck) -> dict:
    """JSON-ready summary: section, loads, combinations, worst elements, equilibrium, timings."""
    r, fr, opt = check.results, check.frame, check.options
    ids = fr.ids
    ratio = check.deflection_ratio()
    gov_names = np.array(r.uls, dtype=object)[r.governing] if r.uls else np.array([""] * fr.n_elements)
    worst_u = worst(r.utilization, ids, combination=gov_names, N_kN=r.N_kN, M_strong_kNm=r.M_strong_kNm,
                    M_weak_kNm=r.M_weak_kNm)
    i_max = int(np.argmax(r.utilization)) if fr.n_elements else 0
    L = fr.lengths()
    totals = {k: (c.total_force(L) * 1e-3).round(3).tolist() for k, c in check.cases.items()}
    sections = sorted({s.name for s in fr.sections})
    out = {
        "check": opt.check,
        "engine": f"OpenSees (openseespy {check.solution.version})",
        "elements": fr.n_elements, "nodes": fr.n_nodes,
        "supports": {"selection": opt.supports if isinstance(opt.supports, str) else list(opt.supports),
                     "kind": opt.support_kind, "count": int(len(check.supports)),
                     "vertices": check.supports[:50].tolist()},
        "connections": opt.connections,
        "section": check.section.as_dict(), "sections": sections,
        "grade": opt.grade, "fy_mpa": opt.fy, "buckling_curve": opt.buckling_curve,
        "buckling_length_factor": opt.buckling_length_factor,
        "min_buckling_factor": float(r.chi.min(initial=1.0)) if r.chi is not None else None,
        "steel_mass_kg": round(fr.steel_mass_kg(), 1),
        "loads_kN": {"characteristic_totals": totals, "input": dataclasses.asdict(opt.loads)},
        "combinations": [{"name": n, "kind": k, "factors": f} for n, k, f in opt.combination_list()],
        "governing_combination": r.uls[int(r.governing[i_max])] if r.uls else None,
        "governing_sls": r.governing_sls,
        "utilization": {"max": float(r.utilization.max(initial=0.0)), "mean": float(r.utilization.mean()),
                        "limit": 1.0, "pass": bool(r.utilization.max(initial=0.0) <= 1.0),
                        "over_1": int((r.utilization > 1.0).sum()), "worst": worst_u, "method": UTILIZATION_NOTE},
        "deflection": {"max_mm": float(r.deflection_mm.max(initial=0.0)), "limit": f"L/{opt.deflection_limit:g}",
                       "max_ratio": float(ratio.max(initial=0.0)), "pass": bool((ratio <= 1.0).all()),
                       "worst": worst(ratio, ids, deflection_mm=r.deflection_mm, limit_mm=r.deflection_limit_mm,
                                      length_mm=L)},
        "displacement": {"max_mm": float(r.displacement_mm.max(initial=0.0)), "span_mm": r.span_mm,
                         "limit_mm": r.displacement_limit_mm,
                         "pass": bool(r.displacement_mm.max(initial=0.0) <= r.displacement_limit_mm),
                         "combination": r.governing_sls},
        "equilibrium": {"relative_residual": r.equilibrium, "max": max(r.equilibrium.values(), default=0.0)},
        "class_4": class_4(check),
        "stability": stability_report(check),
        "pass": check.passes(),
        "seconds": check.seconds,
    }
    return out


STABILITY_NOTE = ("elastic critical load factor alpha_cr of each ULS combination from a linear buckling analysis (K_e + "
                  "alpha K_g, each beam in 4 elements, the combination's first-order axial forces); where alpha_cr < 10 "
                  "(EN 1993-1-1 5.2.1(3)) the combination is solved second order (OpenSees P-Delta) on the frame "
                  "displaced along its first mode by span / n (5.3.2(11)), and its forces replace the first-order "
                  "ones; alpha_cr <= 1 fails")


def stability_report(check: StructureCheck) -> dict | None:
    """report.json's ``stability``: alpha_cr per ULS combination, the lowest with its modes, the
    combinations solved second order and the utilization before and after."""
    st = check.stability
    if st is None:
        return None
    b = st.buckling
    return {"alpha_cr": _finite(st.alpha_cr), "combination": st.combination, "limit": ALPHA_CR_LIMIT,
            "pass": bool(st.alpha_cr > 1.0),
            "alpha_cr_per_combination": {k: _finite(v) for k, v in st.alphas.items()},
            "modes": [_finite(a) for a in (b.alphas.tolist() if b is not None else [])],
            "lower_bound": list(st.lower_bounds), "second_order": dict(st.second_order),
            "imperfection_mm": round(st.imperfection_mm, 2),
            "imperfection": f"first buckling mode x span/{check.options.imperfection:g}",
            "utilization_first_order": st.first_order_utilization,
            "utilization": check.max_utilization, "method": STABILITY_NOTE}


def _finite(v: float):
    """A JSON-ready alpha: None for infinity (nothing compressed)."""
    return round(float(v), 4) if np.isfinite(v) else None


def class_4(check: StructureCheck) -> dict:
    """report.json's ``class_4``: how many beams of each class, the class 4 ones (ids) and the
    :data:`N_WORST` nearest class 4 with their part, c/t, limit, alpha, psi and forces."""
    r, fr = check.results, check.frame
    sc = r.section_class
    names = np.array([s.name for s in fr.sections], dtype=object)[fr.section_of]
    uls = np.array(r.uls or ("",), dtype=object)[r.class_governing]
    top = np.argsort(-sc.ratio, kind="stable")[:N_WORST]
    worst_ = [{"id": fr.ids[i], "section": names[i], "class": int(sc.cls[i]), "part": sc.part[i],
               "c_t": round(float(sc.ct[i]), 2), "limit": round(float(sc.limit[i]), 2),
               "ratio": round(float(sc.ratio[i]), 4), "alpha": round(float(sc.alpha[i]), 4),
               "psi": round(float(sc.psi[i]), 4), "N_kN": round(float(r.class_N_kN[i]), 3),
               "M_top_kNm": round(float(r.class_M_kNm[i]), 4), "combination": uls[i]}
              for i in top.tolist() if sc.ratio[i] > 0]
    ids = check.slender()
    return {"count": int(ids.size), "beams": [fr.ids[i] for i in ids.tolist()],
            "classes": {str(c): int((sc.cls == c).sum()) for c in (1, 2, 3, 4)},
            "max_ratio": float(sc.ratio.max(initial=0.0)), "worst": worst_, "method": CLASS_NOTE}


def beam_table(check: StructureCheck) -> list[dict]:
    """One row per beam: id, section, N, moments, utilization, governing combination, deflection,
    section class (and c/t over its limit)."""
    r, fr = check.results, check.frame
    names = [s.name for s in fr.sections]
    sc = r.section_class
    out = []
    L = fr.lengths()
    for i in range(fr.n_elements):
        out.append({"id": fr.ids[i], "section": names[fr.section_of[i]], "length_mm": round(float(L[i]), 1),
                    "N_kN": round(float(r.N_kN[i]), 3), "M_strong_kNm": round(float(r.M_strong_kNm[i]), 4),
                    "M_weak_kNm": round(float(r.M_weak_kNm[i]), 4), "utilization": round(float(r.utilization[i]), 4),
                    "combination": r.uls[int(r.governing[i])] if r.uls else "",
                    "deflection_mm": round(float(r.deflection_mm[i]), 3),
                    "deflection_limit_mm": round(float(r.deflection_limit_mm[i]), 2),
                    "class": int(sc.cls[i]), "class_ratio": round(float(sc.ratio[i]), 4)})
    return out
