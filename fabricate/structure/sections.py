"""Closed-form properties of the beam sections: solid plate, RHS, tee and I (mm, mm2, mm4, mm3).

Axes (EN 1993 naming): the section's depth ``h`` lies in the beam plane (along the node
axes), its width ``b`` across it.  ``y`` is the strong axis (parallel to the width):
``Iy`` resists bending in the beam plane; ``z`` is the weak axis (in the beam plane,
across the beam): ``Iz`` resists bending out of it.  ``J`` is the St Venant torsion
constant, ``Wy, Wz`` the elastic section moduli (``I / largest fibre distance``), and
``centroid`` the distance of the centroid from the top fibre (the glass side), along
``h``.  Corner radii and fillets are left out (a few per cent on the safe side for RHS
and rolled I sections); the plate's ``J`` is Roark's thin-rectangle series.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from optimize.errors import ConfigError

SHAPES = ("plate", "rhs", "tee", "i")


@dataclass(frozen=True)
class SectionProperties:
    """One section: its dimensions (mm) and properties (mm2, mm4, mm3; mass kg/m with ``density``)."""

    shape: str
    h: float
    b: float
    tw: float
    tf: float
    A: float
    Iy: float
    Iz: float
    J: float
    Wy: float
    Wz: float
    centroid: float

    @property
    def name(self) -> str:
        """``plate 80x300``, ``rhs 300x100x8`` (``x8x12`` when web and flange differ),
        ``i 300x150x7.1x10.7`` (h x b x tw x tf)."""
        if self.shape == "plate":
            return f"plate {self.b:g}x{self.h:g}"
        if self.shape == "rhs":
            return f"rhs {self.h:g}x{self.b:g}x{self.tw:g}" + ("" if self.tf == self.tw else f"x{self.tf:g}")
        return f"{self.shape} {self.h:g}x{self.b:g}x{self.tw:g}x{self.tf:g}"

    def mass_per_m(self, density: float = 7850.0) -> float:
        """kg/m for a steel density in kg/m3."""
        return self.A * 1e-6 * density

    def as_dict(self) -> dict:
        return dict(asdict(self), name=self.name)


def _positive(key: str, **values: float) -> None:
    for k, v in values.items():
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ConfigError(f"{key}.{k} = {v!r}: expected a positive number (mm)")


def plate(b: float, h: float, key: str = "structure.section") -> SectionProperties:
    """Solid rectangle ``b`` (across the beam plane) x ``h`` (in it): today's cut-plate beams."""
    _positive(key, width=b, depth=h)
    long, short = max(b, h), min(b, h)
    r = short / long
    J = long * short ** 3 * (1.0 / 3.0 - 0.21 * r * (1.0 - r ** 4 / 12.0))
    Iy, Iz = b * h ** 3 / 12.0, h * b ** 3 / 12.0
    return SectionProperties("plate", h, b, b, h, b * h, Iy, Iz, J, 2 * Iy / h, 2 * Iz / b, h / 2)


def rhs(h: float, b: float, t: float, key: str = "structure.section") -> SectionProperties:
    """Rectangular hollow section ``h x b``, wall ``t`` (sharp corners; Bredt's ``J``)."""
    _positive(key, depth=h, width=b, web=t)
    if 2 * t >= min(h, b):
        raise ConfigError(f"{key}.web = {t:g}: a wall of {t:g} mm does not fit a {h:g} x {b:g} mm tube "
                          f"(expected web < {min(h, b) / 2:g})")
    hi, bi = h - 2 * t, b - 2 * t
    A = b * h - bi * hi
    Iy = (b * h ** 3 - bi * hi ** 3) / 12.0
    Iz = (h * b ** 3 - hi * bi ** 3) / 12.0
    Am, p = (b - t) * (h - t), 2 * ((b - t) + (h - t))
    J = 4 * Am ** 2 * t / p
    return SectionProperties("rhs", h, b, t, t, A, Iy, Iz, J, 2 * Iy / h, 2 * Iz / b, h / 2)


def i_section(h: float, b: float, tw: float, tf: float, key: str = "structure.section") -> SectionProperties:
    """Doubly symmetric I: depth ``h``, flange width ``b``, web ``tw``, flanges ``tf``."""
    _positive(key, depth=h, width=b, web=tw, flange=tf)
    _fits(key, h, b, tw, tf, flanges=2)
    hw = h - 2 * tf
    A = 2 * b * tf + hw * tw
    Iy = (b * h ** 3 - (b - tw) * hw ** 3) / 12.0
    Iz = (2 * tf * b ** 3 + hw * tw ** 3) / 12.0
    J = (2 * b * tf ** 3 + (h - tf) * tw ** 3) / 3.0
    return SectionProperties("i", h, b, tw, tf, A, Iy, Iz, J, 2 * Iy / h, 2 * Iz / b, h / 2)


def tee(h: float, b: float, tw: float, tf: float, key: str = "structure.section") -> SectionProperties:
    """Tee with its flange on the glass side (top): depth ``h``, flange ``b x tf``, web ``tw``."""
    _positive(key, depth=h, width=b, web=tw, flange=tf)
    _fits(key, h, b, tw, tf, flanges=1)
    hw = h - tf
    Af, Aw = b * tf, hw * tw
    A = Af + Aw
    c = (Af * tf / 2 + Aw * (tf + hw / 2)) / A  # from the top fibre
    Iy = (b * tf ** 3 / 12 + Af * (c - tf / 2) ** 2 + tw * hw ** 3 / 12 + Aw * (tf + hw / 2 - c) ** 2)
    Iz = (tf * b ** 3 + hw * tw ** 3) / 12.0
    J = (b * tf ** 3 + (h - tf / 2) * tw ** 3) / 3.0
    return SectionProperties("tee", h, b, tw, tf, A, Iy, Iz, J, Iy / max(c, h - c), 2 * Iz / b, c)


def _fits(key: str, h: float, b: float, tw: float, tf: float, flanges: int) -> None:
    if tw >= b:
        raise ConfigError(f"{key}.web = {tw:g}: not below the flange width {b:g} mm")
    if flanges * tf >= h:
        raise ConfigError(f"{key}.flange = {tf:g}: {flanges} flange(s) do not fit the depth {h:g} mm")


def section(shape: str, *, depth: float, width: float, web: float | None = None, flange: float | None = None,
            key: str = "structure.section") -> SectionProperties:
    """Properties of a section named by ``shape`` (``plate``, ``rhs``, ``tee``, ``i``); dimensions in mm."""
    if shape == "plate":
        return plate(width, depth, key)
    if shape == "rhs":
        if web is None:
            raise ConfigError(f"{key}.web: missing, an rhs needs its wall thickness (mm)")
        return rhs(depth, width, web, key)
    if shape in ("tee", "i"):
        missing = [k for k, v in (("web", web), ("flange", flange)) if v is None]
        if missing:
            raise ConfigError(f"{key}.{missing[0]}: missing, a {shape} section needs web and flange (mm)")
        return (tee if shape == "tee" else i_section)(depth, width, web, flange, key)
    raise ConfigError(f"{key}.shape = {shape!r}: expected one of {', '.join(SHAPES)}")


def built_section(spec, depth: float) -> SectionProperties:
    """The section the CAD stage welds from plates (``parts.beam``, :mod:`fabricate.cad.sections`), ``depth``
    the layer span (mm): area, ``Iy``, ``Iz`` and the centroid summed over the plates' rectangles (parallel
    axes; flat flanges, i.e. a 180 degree dihedral: the flanges of a real beam tilt by up to the panels'
    half dihedral, which changes ``Iz`` by ``1 - cos`` of it), ``J``: thin-walled, ``sum b t^3 / 3`` for open
    sections (plate: Roark), Bredt's ``4 Am^2 / sum(s / t)`` for the RHS box."""
    from fabricate.cad.sections import section_rectangles

    shape = spec.beam.section
    if shape == "plate":
        return plate(spec.beam_width, depth, "parts")
    R = [(y0, y1, z0, z1) for y0, y1, z0, z1 in section_rectangles(spec, depth)]
    b = [y1 - y0 for y0, y1, _, _ in R]
    h = [z1 - z0 for _, _, z0, z1 in R]
    a = [bi * hi for bi, hi in zip(b, h)]
    A = sum(a)
    zc = sum(ai * (z0 + z1) / 2 for ai, (_, _, z0, z1) in zip(a, R)) / A
    yc = sum(ai * (y0 + y1) / 2 for ai, (y0, y1, _, _) in zip(a, R)) / A
    Iy = sum(bi * hi ** 3 / 12 + ai * ((z0 + z1) / 2 - zc) ** 2 for bi, hi, ai, (_, _, z0, z1) in zip(b, h, a, R))
    Iz = sum(hi * bi ** 3 / 12 + ai * ((y0 + y1) / 2 - yc) ** 2 for bi, hi, ai, (y0, y1, _, _) in zip(b, h, a, R))
    tw, tf, width = spec.web, spec.beam.flange_mm, spec.beam.flange_width_mm
    if shape == "rhs":
        Am = (width - tw) * (depth - tf)
        J = 4 * Am ** 2 / (2 * (width - tw) / tf + 2 * (depth - tf) / tw)
    else:  # open: the web over the full depth, the flange outstands
        J = (depth * tw ** 3 + sum(max(bi, hi) * min(bi, hi) ** 3 for bi, hi in zip(b[1:], h[1:]))) / 3.0
    zmax = max(zc, depth - zc)
    return SectionProperties(shape, depth, width, tw, tf, A, Iy, Iz, J, Iy / zmax, 2 * Iz / width, zc)


@dataclass(frozen=True)
class Part:
    """A plate of a section as EN 1993-1-1 Table 5.2 classifies it: ``name``, ``kind`` (``internal``:
    held on both long edges; ``outstand``: one edge free), its width ``c`` and thickness ``t`` (mm), and
    where it lies along the depth (mm down from the top fibre): a web or stem spans ``z0`` (an outstand's
    held edge) to ``z1`` (its free tip); a flange (``z0 == z1``) lies at one depth, across the beam."""

    name: str
    kind: str
    c: float
    t: float
    z0: float
    z1: float

    @property
    def flange(self) -> bool:
        return self.z0 == self.z1


def parts(sec: SectionProperties) -> tuple[Part, ...]:
    """The plates of ``sec`` that Table 5.2 classifies (none for a solid plate).  ``c`` as the clear
    width without radii: RHS walls ``h - 2 tf - tw`` and ``b - 2 tw - tf`` (``h - 3t``, ``b - 3t`` of the
    Table's note for one wall thickness), I web ``h - 2 tf``, I and tee flange outstands ``(b - tw) / 2``,
    the tee stem ``h - tf`` (an outstand held by the flange)."""
    h, b, tw, tf = sec.h, sec.b, sec.tw, sec.tf
    if sec.shape == "rhs":
        c = h - 2 * tf - tw
        return (Part("web", "internal", c, tw, (h - c) / 2, (h + c) / 2),
                Part("flange", "internal", b - 2 * tw - tf, tf, 0.0, 0.0),
                Part("flange", "internal", b - 2 * tw - tf, tf, h, h))
    if sec.shape == "i":
        return (Part("web", "internal", h - 2 * tf, tw, tf, h - tf),
                Part("flange", "outstand", (b - tw) / 2, tf, 0.0, 0.0),
                Part("flange", "outstand", (b - tw) / 2, tf, h, h))
    if sec.shape == "tee":
        return (Part("stem", "outstand", h - tf, tw, tf, h), Part("flange", "outstand", (b - tw) / 2, tf, 0.0, 0.0))
    return ()


def _layers(sec: SectionProperties) -> tuple[tuple[float, float, float], ...]:
    """``(z0, z1, width)`` bands of the section down its depth (for its plastic neutral axis)."""
    h, b, tw, tf = sec.h, sec.b, sec.tw, sec.tf
    if sec.shape == "rhs":
        return ((0.0, tf, b), (tf, h - tf, 2 * tw), (h - tf, h, b))
    if sec.shape == "i":
        return ((0.0, tf, b), (tf, h - tf, tw), (h - tf, h, b))
    if sec.shape == "tee":
        return ((0.0, tf, b), (tf, h, tw))
    return ((0.0, h, b),)


def plastic_axis(sec: SectionProperties, N, M_top) -> np.ndarray:
    """(k,) depth (mm from the top fibre) of the plastic neutral axis when the section is fully plastic
    under ``N`` (+ tension) and ``M_top`` (+ compresses the top fibre) in proportion: their ratio fixes
    it (pure bending: the equal-area axis; pure compression: the far fibre, pure tension: the near one).
    The compressed side is the top for ``M_top >= 0``, else the bottom.

    With the axis at ``u`` below the compressed fibre, the plastic pair is ``(2 Ac - A, 2 Sc) fy``
    (``Ac`` the area above ``u``, ``Sc`` its first moment about the centroid); it is parallel to
    ``(-N, |M|)`` where ``f(u) = (2 Ac - A) |M| + 2 N Sc`` crosses zero, once, from below.  Within
    one band of the section ``f`` is a quadratic in ``u``: solved in closed form in the band where
    it changes sign."""
    N, M = np.broadcast_arrays(np.asarray(N, dtype=float), np.asarray(M_top, dtype=float))
    h, zc, A = sec.h, sec.centroid, sec.A
    P, Ma = -N, np.abs(M)
    down = M >= 0
    u = np.where(P > 0, h, 0.0)                       # no moment: all compressed, or all in tension
    for top in (True, False):
        sel = (down == top) & (Ma > 0)
        if not sel.any():
            continue
        L = _layers(sec)
        bands, zr = (L, zc) if top else (tuple((h - e, h - a, w) for a, e, w in reversed(L)), h - zc)
        p, m = P[sel], Ma[sel]
        us = np.zeros(p.shape)
        C = Q = 0.0                                   # area and first moment above the band
        for i, (a, e, w) in enumerate(bands):
            Ce, Qe = C + w * (e - a), Q + w * (zr * (e - a) - (e * e - a * a) / 2)
            fa, fe = (2 * C - A) * m - 2 * p * Q, (2 * Ce - A) * m - 2 * p * Qe
            here = (fa <= 0) & ((fe > 0) | (i == len(bands) - 1))
            a2, a1 = w * p, 2 * w * (m - p * (zr - a))  # f(a + v) = a2 v^2 + a1 v + fa
            with np.errstate(divide="ignore", invalid="ignore"):
                root = np.sqrt(np.maximum(a1 * a1 - 4 * a2 * fa, 0.0))
                q = -0.5 * (a1 + np.where(a1 >= 0, root, -root))
                r1, r2 = q / a2, fa / q
            r1, r2 = np.where(np.isfinite(r1), r1, np.inf), np.where(np.isfinite(r2), r2, np.inf)
            off1, off2 = (np.maximum(np.maximum(-r, r - (e - a)), 0.0) for r in (r1, r2))
            v = np.where(off1 <= off2, r1, r2)               # the root inside the band
            us = np.where(here, a + np.clip(v, 0.0, e - a), us)
            C, Q = Ce, Qe
        u[sel] = us if top else h - us
    return u


@dataclass(frozen=True, eq=False)
class SectionClass:
    """The class of a section under its forces, per point (``k``): ``cls`` (1..4, the worst part's),
    ``ratio`` (c/t over the limit of the part nearest class 4: above 1, class 4; 0 when no part is
    compressed), ``part`` (its name), ``ct``, ``limit`` (the largest of its class limits: the class 3
    one, unless a plastic one is larger, which happens to outstands in tension and bending), ``alpha``
    (the compressed fraction of ``c`` in the plastic distribution) and ``psi`` (the elastic stress
    ratio of Table 5.2)."""

    cls: np.ndarray
    ratio: np.ndarray
    part: np.ndarray
    ct: np.ndarray
    limit: np.ndarray
    alpha: np.ndarray
    psi: np.ndarray


def _k_sigma(tip_first: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """Buckling factor of an outstand (EN 1993-1-5 Table 4.2): ``tip_first`` the free tip is the more
    compressed edge (psi = sigma_held / sigma_tip), else the held edge is (psi = sigma_tip / sigma_held)."""
    p = np.clip(psi, -3.0, 1.0)
    tip = 0.57 - 0.21 * p + 0.07 * p ** 2
    q = np.clip(psi, -1.0, 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        held = np.where(q >= 0, 0.578 / (q + 0.34), 1.7 - 5 * q + 17.1 * q ** 2)
    return np.where(tip_first, tip, held)


def _elastic(sec: SectionProperties, p: Part, eps: float, N, M, Mw, floor):
    """Part ``p`` under the elastic stresses of N + M_top (+ |M_weak| on flanges), compression +:
    ``(on, psi, tip, l3)``: compressed (beyond ``floor``, MPa) at all, the stress ratio, the free tip the
    more compressed edge (outstands), the class 3 limit of c/t."""
    zc, A, I = sec.centroid, sec.A, sec.Iy
    if p.flange:
        on = -N / A + M * (zc - p.z0) / I + np.abs(Mw) * (sec.b / 2) / sec.Iz > floor
        l3 = (42 if p.kind == "internal" else 14) * eps
        return on, np.ones(on.shape), np.zeros(on.shape, dtype=bool), np.full(on.shape, float(l3))
    s0, s1 = -N / A + M * (zc - p.z0) / I, -N / A + M * (zc - p.z1) / I
    smax, smin = np.maximum(s0, s1), np.minimum(s0, s1)
    on = smax > np.maximum(floor, 1e-12 * (np.abs(N) / A + np.abs(M) * sec.h / I))
    psi = np.where(on, smin / np.where(on, smax, 1.0), 1.0)
    tip = s1 >= s0                                     # z1 is an outstand's free tip
    if p.kind == "internal":
        l3 = np.where(psi > -1, 42 * eps / (0.67 + 0.33 * psi), 62 * eps * (1 - psi) * np.sqrt(np.maximum(-psi, 0.0)))
    else:
        l3 = np.where(psi >= 1 - 1e-9, 14 * eps, 21 * eps * np.sqrt(_k_sigma(tip, psi)))
    return on, psi, tip, l3


def _loads(N, M_top, M_weak):
    return np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, dtype=float)) for v in (N, M_top, M_weak)))


def classify(sec: SectionProperties, fy: float, N, M_top, M_weak=0.0, floor=0.0) -> SectionClass:
    """The class of ``sec`` (EN 1993-1-1 Table 5.2, ``eps = sqrt(235 / fy)``, ``fy`` the characteristic
    yield strength, MPa) at ``k`` points with axial force ``N`` (N, + tension), strong-axis moment
    ``M_top`` (N mm, + compresses the top fibre) and weak-axis moment ``M_weak`` (N mm, either sign).

    Webs and the tee stem under N + M_top: internal parts (class 1/2 from the plastic compressed
    fraction alpha (:func:`plastic_axis`), ``396 eps / (13 alpha - 1)`` or ``36 eps / alpha``,
    ``456 eps / (13 alpha - 1)`` or ``41.5 eps / alpha``; class 3 from the elastic stress ratio psi,
    ``42 eps / (0.67 + 0.33 psi)`` or ``62 eps (1 - psi) sqrt(-psi)``), outstands (``9 eps / alpha`` and
    ``10 eps / alpha`` with the tip compressed, over ``alpha sqrt(alpha)`` with it in tension; ``14 eps``
    in uniform compression, else ``21 eps sqrt(k_sigma)``, EN 1993-1-5 Table 4.2).  Flanges: as in
    uniform compression (the most restrictive row) wherever N + M_top + |M_weak| compress any point of
    them, else unstressed.  A part with no compression (none above ``floor``, MPa: the round-off of a
    beam's forces where its moment passes zero) has no limit (class 1).  The section's class is its
    worst part's; ``part``, ``ratio`` ... name the part nearest class 4."""
    eps = math.sqrt(235.0 / fy)
    N, M, Mw = _loads(N, M_top, M_weak)
    k = N.shape
    cls, ratio, which = np.ones(k, dtype=np.int64), np.zeros(k), np.full(k, -1)
    ct_, limit, alpha_, psi_ = np.zeros(k), np.full(k, np.inf), np.zeros(k), np.ones(k)
    ps = parts(sec)
    u = plastic_axis(sec, N, M) if any(not p.flange for p in ps) else None
    for j, p in enumerate(ps):
        ct = p.c / p.t
        on, psi, _, l3 = _elastic(sec, p, eps, N, M, Mw, floor)
        if p.flange:
            alpha = np.where(on, 1.0, 0.0)
            l1, l2 = ((33, 38) if p.kind == "internal" else (9, 10))
            l1, l2 = np.full(k, l1 * eps), np.full(k, l2 * eps)
        else:  # the compressed length of the part in the plastic distribution
            top = M >= 0
            inside = np.where(top, np.clip(u, p.z0, p.z1) - p.z0, p.z1 - np.clip(u, p.z0, p.z1))
            alpha = np.where(on, inside / (p.z1 - p.z0), 0.0)
            a = np.maximum(alpha, 1e-12)
            if p.kind == "internal":
                l1 = np.where(a > 0.5, 396 * eps / (13 * a - 1), 36 * eps / a)
                l2 = np.where(a > 0.5, 456 * eps / (13 * a - 1), 41.5 * eps / a)
            else:
                tip = np.where(top, u >= p.z1, u <= p.z1)   # the free tip lies in the compressed zone
                div = np.where(tip, a, a * np.sqrt(a))
                l1, l2 = 9 * eps / div, 10 * eps / div
        c_part = np.where(~on, 1, np.where(ct <= l1, 1, np.where(ct <= l2, 2, np.where(ct <= l3, 3, 4))))
        lim = np.maximum(np.maximum(l1, l2), l3)     # l3, unless a plastic limit is the larger (tension)
        r_part = np.where(on, ct / lim, 0.0)
        take = r_part > ratio
        which = np.where(take, j, which)
        ct_ = np.where(take, ct, ct_)
        limit, alpha_, psi_ = np.where(take, lim, limit), np.where(take, alpha, alpha_), np.where(take, psi, psi_)
        ratio = np.where(take, r_part, ratio)
        cls = np.maximum(cls, c_part)
    names = np.array([""] + [p.name for p in ps], dtype=object)
    return SectionClass(cls, ratio, names[which + 1], ct_, limit, alpha_, psi_)
