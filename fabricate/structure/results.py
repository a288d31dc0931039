"""Per beam results of the solved frame: forces, utilization, deflection; the worst ones named.

Internal forces along an element follow from its end forces and its uniform line load
``w`` (local): cutting at ``x`` from end 1,
``N(x) = -(F1x + wx x)``, ``Mz(x) = -M1z + F1y x + wy x^2 / 2`` (bending in the beam plane,
the section's strong axis), ``My(x) = -M1y - F1z x - wz x^2 / 2`` (weak axis), ``T = -M1x``,
evaluated at :data:`SAMPLES` points and at the parabolas' vertices.

Utilization: the larger of the elastic cross-section check (EN 1993-1-1 6.2.1(7), linear
interaction) ``|N| / (A fy) + |M_strong| / (Wy fy) + |M_weak| / (Wz fy)`` and the same with the
compression divided by the flexural buckling factor ``chi`` (6.3.1, the weaker axis, buckling
length = the beam length times ``buckling_length_factor``, imperfection factor ``alpha``:
interaction factors taken as 1); ``fy = f_y / gamma_M``; the max over the element and the ULS
combinations.  Shear, torsion, lateral-torsional buckling and connections are not checked.

Section class (EN 1993-1-1 Table 5.2, :func:`fabricate.structure.sections.classify`): at every
point of every ULS combination, from ``N`` and the strong-axis moment (its sign turned to the
section's top fibre, ``Frame.top``; both signs where that is unknown) with the weak-axis one on the
flanges; a beam's class is its worst, and the point nearest class 4 is kept with its forces.

Deflection of a beam relative to the chord between its nodes: ``EI v'' = M(x)`` with
``v(0) = v(L) = 0`` (exact for the end moments and the uniform load), both planes, the
magnitude; against ``L / deflection_limit``.  Node displacements (the whole structure)
against ``span / deflection_limit``.  Both for the SLS combinations.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .sections import SectionClass, classify

SAMPLES = 17
N_WORST = 5
ROUND_OFF = 1e-9
"""Stresses below this fraction of a beam's largest (over its points, per combination) are round-off:
no compression for the section class (where a moment passes zero)."""


def internal_forces(F: np.ndarray, w: np.ndarray, L: np.ndarray, n: int = SAMPLES):
    """Internal forces along each element.

    F : (e, 12) end forces (local), w : (e, 3) local line load, L : (e,) lengths.
    Returns ``x (e, s)``, ``N, M_strong, M_weak (e, s)`` and ``T (e,)`` (N, N mm) at ``s = n + 2``
    points: ``n`` evenly spaced ones and the two parabolas' vertices (clipped to the element).
    """
    xs = np.linspace(0.0, 1.0, n)[None, :] * L[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        vz = np.where(w[:, 1] != 0, -F[:, 1] / w[:, 1], 0.0)
        vy = np.where(w[:, 2] != 0, -F[:, 2] / w[:, 2], 0.0)
    x = np.concatenate([xs, np.clip(np.stack([vz, vy], axis=1), 0.0, L[:, None])], axis=1)
    N = -(F[:, [0]] + w[:, [0]] * x)
    Ms = -F[:, [5]] + F[:, [1]] * x + 0.5 * w[:, [1]] * x ** 2
    Mw = -F[:, [4]] - F[:, [2]] * x - 0.5 * w[:, [2]] * x ** 2
    return x, N, Ms, Mw, -F[:, 3]


def buckling_factor(A: np.ndarray, I_min: np.ndarray, L_cr: np.ndarray, E: float, fy: float,
                    alpha: float) -> np.ndarray:
    """(e,) float flexural buckling reduction ``chi <= 1`` (EN 1993-1-1 6.3.1.2)."""
    lam = np.sqrt(A * fy / (np.pi ** 2 * E * I_min / L_cr ** 2))
    phi = 0.5 * (1.0 + alpha * (lam - 0.2) + lam ** 2)
    return np.minimum(1.0, 1.0 / (phi + np.sqrt(np.maximum(phi ** 2 - lam ** 2, 0.0))))


def utilization(N, Ms, Mw, A, Wy, Wz, chi, fy: float) -> np.ndarray:
    """Utilization of sections ``A, Wy, Wz, chi`` (broadcast) under ``N`` (+ tension), ``Ms``, ``Mw``
    (N, N mm): the larger of the cross-section and the flexural buckling check (module docstring)."""
    bend = np.abs(Ms) / (Wy * fy) + np.abs(Mw) / (Wz * fy)
    return np.maximum(np.abs(N) / (A * fy), np.maximum(-N, 0.0) / (chi * A * fy)) + bend


def chord_deflection(F: np.ndarray, w: np.ndarray, L: np.ndarray, EI_strong: np.ndarray, EI_weak: np.ndarray,
                     n: int = SAMPLES) -> np.ndarray:
    """(e,) float max deflection (mm) of each element relative to the chord of its ends.

    Solves ``EI v'' = c0 + c1 x + c2 x^2``, ``v(0) = v(L) = 0`` in both planes (see the module).
    """
    x = np.linspace(0.0, 1.0, n)[None, :] * L[:, None]

    def plane(c0, c1, c2, EI):
        C = -(c0 * L / 2 + c1 * L ** 2 / 6 + c2 * L ** 3 / 12)
        return (c0[:, None] * x ** 2 / 2 + c1[:, None] * x ** 3 / 6 + c2[:, None] * x ** 4 / 12
                + C[:, None] * x) / EI[:, None]

    v = plane(-F[:, 5], F[:, 1], 0.5 * w[:, 1], EI_strong)
    u = plane(-F[:, 4], -F[:, 2], -0.5 * w[:, 2], EI_weak)
    return np.sqrt(v ** 2 + u ** 2).max(axis=1)


@dataclass(frozen=True, eq=False)
class Results:
    """Per element governing values (``e`` elements) and the summary.

    N_kN (e,) axial force of the governing ULS combination at the governing point (+ tension);
    M_strong_kNm, M_weak_kNm, T_kNm (e,) max |moment| of that combination; utilization (e,);
    governing (e,) int index into ``uls``; deflection_mm, deflection_limit_mm (e,) (worst SLS);
    displacement_mm (e,) worst node displacement of the element's ends (SLS); node_displacement
    (n, 3) of the governing SLS combination; equilibrium {case: relative residual}; chi (e,)
    flexural buckling factors.
    section_class : per element SectionClass (``cls`` the worst along the beam and over the ULS
    combinations; the rest at the point nearest class 4), with that point's ``class_N_kN``,
    ``class_M_kNm`` (strong axis, + compresses the top fibre) and ``class_governing`` (index into ``uls``).
    """

    N_kN: np.ndarray
    M_strong_kNm: np.ndarray
    M_weak_kNm: np.ndarray
    T_kNm: np.ndarray
    utilization: np.ndarray
    governing: np.ndarray
    deflection_mm: np.ndarray
    deflection_limit_mm: np.ndarray
    displacement_mm: np.ndarray
    node_displacement: np.ndarray
    uls: tuple
    sls: tuple
    governing_sls: str
    span_mm: float
    displacement_limit_mm: float
    equilibrium: dict = field(default_factory=dict)
    chi: np.ndarray | None = None
    section_class: SectionClass | None = None
    class_N_kN: np.ndarray | None = None
    class_M_kNm: np.ndarray | None = None
    class_governing: np.ndarray | None = None


def equilibrium(frame, cases, solution) -> dict[str, float]:
    """``{case: |sum of reactions + sum of loads| / |sum of loads|}`` (forces; 0 for an empty case; a
    case whose loads sum to zero: over the sum of their magnitudes)."""
    L = frame.lengths()
    out = {}
    for name, case in cases.items():
        load = case.total_force(L)
        reac = solution.reactions[name][:, :3].sum(axis=0)
        # a self-equilibrated case (temperature: nodal loads that sum to zero) against its loads' size
        size = float(np.abs(case.nodal[:, :3]).sum() + (np.abs(case.line) * L[:, None]).sum())
        scale = float(np.linalg.norm(load))
        scale = scale if scale > 1e-6 * size else size
        out[name] = float(np.linalg.norm(load + reac) / scale) if scale > 0 else float(np.linalg.norm(reac))
    return out


def evaluate(frame, cases, solution, combinations, *, fy: float, deflection_limit: float,
             span_mm: float, alpha: float = 0.49, buckling_length_factor: float = 1.0,
             fy_class: float | None = None) -> Results:
    """Combine the solved basic cases (superposition) and evaluate every element.

    combinations : ``[(name, "uls" | "sls", {case: factor})]``; fy : design yield strength, MPa;
    fy_class : the characteristic one of the section class's ``eps`` (default ``fy``).
    """
    L = frame.lengths()
    A, Wy, Wz = frame.prop("A"), frame.prop("Wy"), frame.prop("Wz")
    EIs, EIw = frame.E * frame.prop("Iy"), frame.E * frame.prop("Iz")
    chi = buckling_factor(A, np.minimum(frame.prop("Iy"), frame.prop("Iz")), L * buckling_length_factor,
                          frame.E, fy, alpha)
    e = frame.n_elements
    uls = [c for c in combinations if c[1] == "uls"]
    sls = [c for c in combinations if c[1] == "sls"]

    def mix(store, factors):
        return sum(f * store[k] for k, f in factors.items())

    util = np.full(e, -1.0)
    gov = np.zeros(e, dtype=np.int64)
    N_g, Ms_g, Mw_g, T_g = (np.zeros(e) for _ in range(4))
    rows = np.arange(e)
    sections = _Classes(frame, fy if fy_class is None else fy_class)
    for ci, (_, _, factors) in enumerate(uls):
        F, w = mix(solution.end_forces, factors), mix(solution.line_local, factors)
        x, N, Ms, Mw, T = internal_forces(F, w, L)
        u = utilization(N, Ms, Mw, A[:, None], Wy[:, None], Wz[:, None], chi[:, None], fy)
        j = np.argmax(u, axis=1)
        better = u[rows, j] > util
        util = np.where(better, u[rows, j], util)
        gov = np.where(better, ci, gov)
        N_g = np.where(better, N[rows, j], N_g)
        Ms_g = np.where(better, np.abs(Ms).max(axis=1), Ms_g)
        Mw_g = np.where(better, np.abs(Mw).max(axis=1), Mw_g)
        T_g = np.where(better, np.abs(T), T_g)
        sections.add(ci, N, Ms, Mw)
    defl = np.zeros(e)
    disp = np.zeros(e)
    node_disp = np.zeros((frame.n_nodes, 3))
    worst_sls, gov_sls = -1.0, ""
    for name, _, factors in sls:
        F, w = mix(solution.end_forces, factors), mix(solution.line_local, factors)
        defl = np.maximum(defl, chord_deflection(F, w, L, EIs, EIw))
        U = mix(solution.displacements, factors)[:, :3]
        un = np.linalg.norm(U, axis=1)
        disp = np.maximum(disp, un[frame.elements].max(axis=1))
        if un.max() > worst_sls:
            worst_sls, gov_sls, node_disp = float(un.max()), name, U
    return Results(N_kN=N_g * 1e-3, M_strong_kNm=Ms_g * 1e-6, M_weak_kNm=Mw_g * 1e-6, T_kNm=T_g * 1e-6,
                   utilization=np.maximum(util, 0.0), governing=gov, deflection_mm=defl,
                   deflection_limit_mm=L / deflection_limit, displacement_mm=disp, node_displacement=node_disp,
                   uls=tuple(c[0] for c in uls), sls=tuple(c[0] for c in sls), governing_sls=gov_sls,
                   span_mm=float(span_mm), displacement_limit_mm=float(span_mm / deflection_limit),
                   equilibrium=equilibrium(frame, cases, solution), chi=chi, section_class=sections.result(),
                   class_N_kN=sections.N * 1e-3, class_M_kNm=sections.M * 1e-6, class_governing=sections.governing)


class _Classes:
    """The section class of every element over the points of the ULS combinations (:meth:`add` each)."""

    def __init__(self, frame, fy: float):
        e = frame.n_elements
        self.frame, self.fy = frame, fy
        self.top = np.ones(e) if frame.top is None else np.asarray(frame.top, dtype=float)
        self.signs = (1.0,) if frame.top is not None else (1.0, -1.0)
        self.groups = [(frame.sections[i], np.nonzero(frame.section_of == i)[0])
                       for i in np.unique(frame.section_of).tolist()]
        self.ratio, self.cls = np.full(e, -1.0), np.ones(e, dtype=np.int64)
        self.N, self.M, self.Mw, self.floor = np.zeros(e), np.zeros(e), np.zeros(e), np.zeros(e)
        self.governing = np.zeros(e, dtype=np.int64)

    def add(self, ci: int, N: np.ndarray, Ms: np.ndarray, Mw: np.ndarray) -> None:
        """Combination ``ci``'s internal forces ``(e, s)``: N (+ tension), strong and weak moments (N mm)."""
        Mt = Ms * self.top[:, None]
        for sec, ix in self.groups:
            rows = np.arange(len(ix))
            stress = np.abs(N[ix]) / sec.A + np.abs(Mt[ix]) * sec.h / sec.Iy + np.abs(Mw[ix]) * sec.b / sec.Iz
            floor = ROUND_OFF * stress.max(axis=1, keepdims=True)   # below it a stress is the forces' round-off
            for sg in self.signs:
                got = classify(sec, self.fy, N[ix], sg * Mt[ix], Mw[ix], floor)
                j = np.argmax(got.ratio, axis=1)
                better = got.ratio[rows, j] > self.ratio[ix]
                at = ix[better]
                self.ratio[at] = got.ratio[rows, j][better]
                self.N[at], self.M[at] = N[ix, j][better], sg * Mt[ix, j][better]
                self.Mw[at], self.governing[at] = Mw[ix, j][better], ci
                self.floor[at] = floor[better, 0]
                self.cls[ix] = np.maximum(self.cls[ix], got.cls.max(axis=1))

    def result(self) -> SectionClass:
        """The details (part, ratio, c/t, limit, alpha, psi) at each element's point nearest class 4."""
        e = self.frame.n_elements
        out = SectionClass(self.cls, np.zeros(e), np.full(e, "", dtype=object), np.zeros(e), np.full(e, np.inf),
                           np.zeros(e), np.ones(e))
        for sec, ix in self.groups:
            got = classify(sec, self.fy, self.N[ix], self.M[ix], self.Mw[ix], self.floor[ix])
            for name in ("ratio", "part", "ct", "limit", "alpha", "psi"):
                getattr(out, name)[ix] = getattr(got, name)
        return out


def worst(values: np.ndarray, ids, k: int = N_WORST, **columns) -> list[dict]:
    """The ``k`` largest ``values (e,)`` as ``[{"id", "value", column: value}]``."""
    order = np.argsort(-values, kind="stable")[:k]
    out = []
    for i in order.tolist():
        row = {"id": ids[i], "value": float(values[i])}
        for key, col in columns.items():
            v = col[i]
            row[key] = v if isinstance(v, str) else float(v)
        out.append(row)
    return out
