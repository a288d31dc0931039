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


def slender_part(sec: SectionProperties, fy: float) -> str | None:
    """The part of ``sec`` beyond the class 3 width-to-thickness limit of EN 1993-1-1 Table 5.2
    (local buckling, class 4, is not covered by the check), or None.

    Limits with ``eps = sqrt(235 / fy)``: I and RHS webs (bending) ``c/t <= 124 eps``; RHS flanges
    (the compressed wall in bending) ``42 eps``; I flange outstands and tee stems ``14 eps``; tee
    flange outstands ``14 eps``.  Solid plates have no thin parts.  ``c`` as the clear width
    (without radii: ``h - 3t`` for RHS walls).
    """
    eps = math.sqrt(235.0 / fy)
    parts: list[tuple[str, float, float]] = []
    if sec.shape == "rhs":
        parts = [("web", (sec.h - 3 * sec.tw) / sec.tw, 124 * eps), ("flange", (sec.b - 3 * sec.tw) / sec.tw, 42 * eps)]
    elif sec.shape == "i":
        parts = [("web", (sec.h - 2 * sec.tf) / sec.tw, 124 * eps), ("flange", (sec.b - sec.tw) / 2 / sec.tf, 14 * eps)]
    elif sec.shape == "tee":
        parts = [("stem", (sec.h - sec.tf) / sec.tw, 14 * eps), ("flange", (sec.b - sec.tw) / 2 / sec.tf, 14 * eps)]
    for name, ct, limit in parts:
        if ct > limit:
            return f"{sec.name}: {name} c/t = {ct:.1f} > {limit:.1f} (class 4)"
    return None
