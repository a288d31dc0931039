"""Built-in designs: parametric starting meshes for the modelling loop, in millimetres.

Every design is a function of keyword parameters (sizes in mm, counts,
``noise`` as a fraction of the mean edge length with its ``seed``) returning a
:class:`Design`: the starting mesh (the control mesh when ``levels > 0``), how
many rounds of which subdivision scheme to run, and the target to perturb to
(:func:`optimize.modelling.hierarchy.subdivide_and_perturb` runs it).  ``DESIGNS`` maps
names to functions; :func:`describe` lists them with their parameters.

=====================  ==================================================  =====================
design                 what                                                levels, scheme, target
=====================  ==================================================  =====================
railway_station        long undulating canopy, ~10 x 4 control quads       3 catmull_clark conical
trefoil_band           Moebius band along a trefoil knot, 42 -> 336 quads  3 chaikin strip
developable_strips     several wavy strips side by side (paper Fig. 16)    2 chaikin strip
hypar_roof             hyperbolic paraboloid (parabola or ruling grid)     0 conical
dome                   spherical cap of revolution (PQ, conical, circular) 0 conical
torus_patch            patch of a torus of revolution                      0 circular
freeform_canopy        height field with seeded bumps                      2 catmull_clark conical
tunnel                 tunnel forking in two (pair of pants), 784 quads    0 conical
=====================  ==================================================  =====================
"""
from __future__ import annotations

import inspect
import re

import numpy as np

from ..errors import ConfigError
from ..mesh import Mesh
from .design_params import (MAX_COUNT, MAX_NOISE, MAX_SIZE_MM, UNITS, Design,  # noqa: F401 (re-exported)
                            int_param as _int, noise_param as _noise, noisy as _noisy, pos_param as _pos)
from .design_tunnel import tunnel
from .shapes import dome_profile, grid, revolution, translational
from .strips import join_meshes, strip_mesh

__all__ = ["Design", "DESIGNS", "describe", "parse_params", "UNITS"]

# -- the designs -----------------------------------------------------------------------

def railway_station(*, length: float = 80000.0, width: float = 24000.0, rise: float = 7000.0,
                    wave: float = 2000.0, waves: int = 2, nu: int = 10, nv: int = 4, levels: int = 3,
                    noise: float = 0.0, seed: int = 0) -> Design:
    """A long undulating canopy (paper Fig. 1, 14) made conical.

    length : canopy length along x (mm)
    width : canopy span along y (mm)
    rise : height of the vault crown above its edges (mm)
    wave : amplitude of the undulation of the crown and the plan outline (mm)
    waves : number of undulations along the length
    nu : control quads along the length
    nv : control quads across the span
    levels : Catmull-Clark rounds (3 levels of 10 x 4 give 2,673 vertices)
    noise : control-vertex noise, fraction of the mean edge length
    seed : noise seed
    """
    p = dict(locals())  # the parameters as given
    name = "railway_station"
    L, W, H = (_pos(name, k, p[k]) for k in ("length", "width", "rise"))
    A = _pos(name, "wave", wave, zero=True)
    k = _int(name, "waves", waves, 0, 100)
    nu, nv = _int(name, "nu", nu, 2, MAX_COUNT), _int(name, "nv", nv, 2, MAX_COUNT)
    levels = _int(name, "levels", levels, 0, 6)
    noise = _noise(name, noise)

    def lift(X, Y):
        s = np.sin(2 * np.pi * k * X / L)
        return H * (1.0 - (2.0 * Y / W) ** 2) + A * s * np.cos(np.pi * Y / W)

    m = grid(nu + 1, nv + 1, (L, W), name=name)
    X, Y = m.V[:, 0], m.V[:, 1] - W / 2
    Y = Y * (1.0 + 0.5 * A / W * np.cos(2 * np.pi * k * X / L))  # the plan outline breathes
    V = np.stack([X, Y, lift(X, Y)], axis=1)
    mesh = _noisy(m.with_vertices(V, name=name), noise, _int(name, "seed", seed, 0, 2 ** 31))
    return Design(name, mesh, levels, "catmull_clark", "conical",
                  f"undulating canopy {L / 1000:g} x {W / 1000:g} m, {nu} x {nv} control quads", p)


def _frenet(t: np.ndarray, scale: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Trefoil knot ``(r, 3)`` points, unit principal normal, binormal and Darboux direction at ``t``.

    The Darboux direction ``(tau T + kappa B) / |...|`` is the ruling of the
    knot's rectifying developable (the developable surface through the knot
    whose normals are the principal normals), so a band along it is
    developable up to the discretization.
    """
    c = np.stack([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)], 1)
    d1 = np.stack([np.cos(t) + 4 * np.cos(2 * t), -np.sin(t) + 4 * np.sin(2 * t), -3 * np.cos(3 * t)], 1)
    d2 = np.stack([-np.sin(t) - 8 * np.sin(2 * t), -np.cos(t) + 8 * np.cos(2 * t), 9 * np.sin(3 * t)], 1)
    d3 = np.stack([-np.cos(t) - 16 * np.cos(2 * t), np.sin(t) - 16 * np.sin(2 * t), 27 * np.cos(3 * t)], 1)
    T = d1 / np.linalg.norm(d1, axis=1, keepdims=True)
    N = d2 - np.einsum("ij,ij->i", d2, T)[:, None] * T
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    B = np.cross(T, N)
    x = np.cross(d1, d2)
    x2 = np.einsum("ij,ij->i", x, x)
    kappa = np.sqrt(x2) / np.linalg.norm(d1, axis=1) ** 3
    tau = np.einsum("ij,ij->i", x, d3) / x2
    D = tau[:, None] * T + kappa[:, None] * B
    return scale * c, N, B, D / np.linalg.norm(D, axis=1, keepdims=True)


def trefoil_band_mesh(rulings: int = 336, width: float = 0.3, *, scale: float = 1.0, twist: bool = True,
                      name: str = "trefoil_band") -> Mesh:
    """The band of ``rulings`` rulings (as many quads, closed) along the trefoil knot scaled by ``scale``.

    Rulings of length ``width`` (the knot's units times ``scale``).  ``twist``: the
    paper's Moebius band (Fig. 9/11 of Liu et al. 2006: 336 quads), the ruling turning
    half a turn about the knot relative to the Frenet frame (a smooth ruled surface, not
    developable until optimized with target ``strip``); otherwise the two-sided band along
    the Darboux direction, on the knot's rectifying developable.  Vertices are numbered as
    :func:`optimize.modelling.strips.strip_mesh` numbers them.
    """
    t = np.linspace(0.0, 2 * np.pi, rulings, endpoint=False)
    c, N, B, D = _frenet(t, scale)
    if twist:  # the paper's band: the ruling turns half a turn about the knot
        d = np.cos(0.5 * t)[:, None] * N + np.sin(0.5 * t)[:, None] * B
    else:  # nearly developable from the start: the optimizer moves little, no ruling collapses
        d = D
    return strip_mesh(c - 0.5 * width * d, c + 0.5 * width * d, closed=True, twist=bool(twist), name=name)


def trefoil_band(*, scale: float = 1000.0, width: float = 500.0, rulings: int = 42, levels: int = 3,
                 twist: bool = True, noise: float = 0.0, seed: int = 0) -> Design:
    """A PQ strip along a trefoil knot with a half twist (paper Fig. 9), made developable.

    scale : mm per unit of the knot (sin t + 2 sin 2t, cos t - 2 cos 2t, -sin 3t); ~6 m across at 1000
    width : band width (mm), below 1.2 x scale so the strands do not touch
    rulings : rulings of the control band (42 and 3 Chaikin levels give 336 quads)
    levels : Chaikin rounds on the band's boundary
    twist : a half twist (a Moebius band, rulings turning about the knot); otherwise a closed
        two-sided band on the knot's rectifying developable (rulings along the Darboux vector)
    noise : control-vertex noise, fraction of the mean edge length
    seed : noise seed
    """
    p = dict(locals())  # the parameters as given
    name = "trefoil_band"
    s, w = _pos(name, "scale", scale), _pos(name, "width", width)
    if not isinstance(twist, (bool, np.bool_)):
        raise ConfigError(f"design {name}: parameter twist={twist!r}, expected true or false")
    if w >= 1.2 * s:
        raise ConfigError(f"design {name}: parameter width={width!r}, expected less than 1.2 x scale "
                          f"= {1.2 * s:g} mm (wider bands run through the neighbouring strand)")
    r = _int(name, "rulings", rulings, 6, 2000)
    levels = _int(name, "levels", levels, 0, 8)
    mesh = trefoil_band_mesh(r, w, scale=s, twist=bool(twist), name=name)
    mesh = _noisy(mesh, _noise(name, noise), _int(name, "seed", seed, 0, 2 ** 31))
    return Design(name, mesh, levels, "chaikin", "strip",
                  f"{'Moebius' if twist else 'closed'} band along a trefoil knot, {r} control rulings", p)


def developable_strips(*, count: int = 4, rulings: int = 9, length: float = 8000.0, width: float = 1200.0,
                       gap: float = 600.0, amplitude: float = 1000.0, turn_deg: float = 20.0,
                       levels: int = 2, noise: float = 0.0, seed: int = 0) -> Design:
    """Several wavy strips side by side (paper Fig. 16), each made developable.

    count : number of strips
    rulings : control rulings per strip
    length : strip length along x (mm)
    width : strip width across its centre line (mm)
    gap : clear distance between neighbouring strips (mm)
    amplitude : vertical wave amplitude of the strip centre lines (mm)
    turn_deg : how far a strip turns about its centre line, in step with the wave (degrees)
    levels : Chaikin rounds
    noise : control-vertex noise, fraction of the mean edge length
    seed : noise seed

    Each control strip is already nearly developable, so the optimizer keeps
    its shape: a strip whose tangent plane turns by ``ang`` about a centre
    line of normal curvature ``kappa_n`` is developable only with rulings
    leaning ``psi`` from across the strip, ``tan psi = -tau_g / kappa_n``
    (geodesic torsion ``ang'`` over normal curvature).  The turn follows the slope
    of the wave (``ang = turn cos``), so ``ang'`` vanishes where the wave has
    its inflections and ``psi`` stays bounded; the singular curve then stays
    well outside the strips (paper section 6).  A turn that would lean the
    rulings by more than :data:`MAX_LEAN_DEG` is refused (thin sheared quads,
    the singular curve running into the strip).
    """
    p = dict(locals())  # the parameters as given
    name = "developable_strips"
    n = _int(name, "count", count, 1, 50)
    r = _int(name, "rulings", rulings, 3, 2000)
    L, w = _pos(name, "length", length), _pos(name, "width", width)
    g, A = _pos(name, "gap", gap, zero=True), _pos(name, "amplitude", amplitude, zero=True)
    if isinstance(turn_deg, bool) or not isinstance(turn_deg, (int, float, np.integer, np.floating)) \
            or not -90.0 <= turn_deg <= 90.0:
        raise ConfigError(f"design {name}: parameter turn_deg={turn_deg!r}, expected a number in [-90, 90]")
    turn = np.radians(float(turn_deg))
    levels = _int(name, "levels", levels, 0, 8)
    k = 2 * np.pi / L  # wave number: one wave along the length
    lean = _strip_lean(turn, A * k)
    if not lean <= MAX_LEAN_DEG:
        raise ConfigError(
            f"design {name}: parameters turn_deg={turn_deg!r}, amplitude={amplitude!r}: a developable strip "
            f"turning that much needs rulings leaning {lean:.0f} deg from across the strip, expected at most "
            f"{MAX_LEAN_DEG:g} deg; use a smaller turn_deg or a larger amplitude")
    x = np.linspace(0.0, L, r)
    strips = []
    for i in range(n):  # a handful of strips
        th = k * x + np.pi * i / n
        centre = np.stack([x, np.full(r, i * (w + g)), A * np.sin(th)], axis=1)
        t = np.stack([np.ones(r), np.zeros(r), A * k * np.cos(th)], axis=1)
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        y = np.broadcast_to([0.0, 1.0, 0.0], t.shape)
        ang = turn * np.cos(th)
        across = np.cos(ang)[:, None] * y + np.sin(ang)[:, None] * np.cross(t, y)
        psi = _strip_psi(turn, A * k, th)
        d = (across + np.tan(psi)[:, None] * t)  # a ruling reaching `width` across the centre line
        strips.append(strip_mesh(centre - 0.5 * w * d, centre + 0.5 * w * d, name=f"{name}{i}"))
    mesh = _noisy(join_meshes(strips, name=name), _noise(name, noise),
                  _int(name, "seed", seed, 0, 2 ** 31))
    return Design(name, mesh, levels, "chaikin", "strip",
                  f"{n} wavy strips {L / 1000:g} m long, {w / 1000:g} m wide, turning {turn_deg:g} deg", p)


MAX_LEAN_DEG = 60.0
"""Largest lean of the control rulings of ``developable_strips`` from across the strip (degrees)."""


def _strip_psi(turn: float, ak: float, th: np.ndarray) -> np.ndarray:
    """(r,) float: lean of the developable rulings (radians) along a centre line ``z = A sin(th)``
    whose tangent plane turns by ``turn cos(th)``; ``ak`` = amplitude x wave number.

    ``tan psi = -(n . e') / (n . t')`` (``e`` across the strip, ``t`` along it,
    ``n = t x e``, derivatives in x): ``n . e' = ang' = -turn k sin th`` and
    ``n . t' = -A k^2 sin th cos(ang) / (1 + (A k cos th)^2)``; the ``sin th``
    cancels, so ``psi`` is finite everywhere (0 for ``turn = 0``).  The
    control strip is then developable up to O(h^2) in the ruling spacing.
    """
    if turn == 0.0:
        return np.zeros_like(th)
    ang = turn * np.cos(th)
    return np.arctan(-turn * (1.0 + (ak * np.cos(th)) ** 2) / (ak * np.cos(ang)))


def _strip_lean(turn: float, ak: float) -> float:
    """Largest ``|psi|`` of :func:`_strip_psi` (degrees; inf for a turn without a wave)."""
    if turn == 0.0:
        return 0.0
    if ak == 0.0:
        return float("inf")
    return float(np.degrees(np.abs(_strip_psi(turn, ak, np.array([0.0, np.pi]))).max()))


def hypar_roof(*, size: float = 12000.0, rise: float = 3000.0, n: int = 12, grid_kind: str = "parabolas",
               noise: float = 0.0, seed: int = 0) -> Design:
    """A hyperbolic paraboloid roof made conical.

    size : plan size (mm): side of the square ("rulings") or its diagonal ("parabolas")
    rise : height of the saddle's high points above its centre (mm)
    n : quads per side
    grid_kind : "parabolas" (translational net: PQ exactly, not conical) or "rulings" (straight, not PQ)
    noise : vertex noise, fraction of the mean edge length
    seed : noise seed
    """
    p = dict(locals())  # the parameters as given
    name = "hypar_roof"
    s, h = _pos(name, "size", size), _pos(name, "rise", rise)
    n = _int(name, "n", n, 1, MAX_COUNT)
    if not isinstance(grid_kind, str) or grid_kind not in ("parabolas", "rulings"):
        raise ConfigError(f"design {name}: parameter grid_kind={grid_kind!r}, "
                          "expected 'parabolas' or 'rulings'")
    u = np.linspace(-0.5 * s, 0.5 * s, n + 1)
    if grid_kind == "rulings":
        m = grid(n + 1, n + 1, (s, s), height=lambda X, Y: 4 * h * (X - s / 2) * (Y - s / 2) / s ** 2,
                 name=name)
        m = m.with_vertices(m.V - [s / 2, s / 2, 0.0])
    else:  # x = (u + v) / 2, y = (u - v) / 2 over a square in (u, v): z = 4 h (u^2 - v^2) / s^2
        a = np.stack([0.5 * u, 0.5 * u, 4 * h * u ** 2 / s ** 2], axis=1)
        b = np.stack([0.5 * u, -0.5 * u, -4 * h * u ** 2 / s ** 2], axis=1)
        m = translational(a, b, name=name)
    mesh = _noisy(m, _noise(name, noise), _int(name, "seed", seed, 0, 2 ** 31))
    return Design(name, mesh, 0, "catmull_clark", "conical",
                  f"hyperbolic paraboloid, {n} x {n} quads on its {grid_kind} grid", p)


def dome(*, radius: float = 10000.0, rise: float = 4000.0, meridians: int = 24, rings: int = 8,
         noise: float = 0.0, seed: int = 0) -> Design:
    """A spherical-cap dome of revolution: PQ, conical and circular by construction.

    radius : base radius (mm)
    rise : height of the cap (mm)
    meridians : quads around
    rings : vertex rings from the base to the top opening
    noise : vertex noise, fraction of the mean edge length (0 keeps it exactly conical)
    seed : noise seed
    """
    p = dict(locals())  # the parameters as given
    name = "dome"
    R, h = _pos(name, "radius", radius), _pos(name, "rise", rise)
    m = revolution(dome_profile(R, h, _int(name, "rings", rings, 2, MAX_COUNT)),
                   _int(name, "meridians", meridians, 3, MAX_COUNT), name=name)
    mesh = _noisy(m, _noise(name, noise), _int(name, "seed", seed, 0, 2 ** 31))
    return Design(name, mesh, 0, "catmull_clark", "conical",
                  f"dome of revolution, {R / 1000:g} m radius, {h / 1000:g} m rise", p)


def torus_patch(*, major: float = 10000.0, minor: float = 4000.0, sweep_deg: float = 90.0,
                arc_deg: float = 150.0, nu: int = 16, nv: int = 10, noise: float = 0.0,
                seed: int = 0) -> Design:
    """A patch of a torus of revolution (outer side): PQ, conical and circular by construction.

    major : distance of the tube centre from the axis (mm)
    minor : tube radius (mm), less than major
    sweep_deg : angle swept about the axis (degrees)
    arc_deg : angle of the tube cross-section arc, centred on the outside (degrees)
    nu : quads about the axis
    nv : quads along the cross-section arc
    noise : vertex noise, fraction of the mean edge length
    seed : noise seed
    """
    p = dict(locals())  # the parameters as given
    name = "torus_patch"
    R, r = _pos(name, "major", major), _pos(name, "minor", minor)
    if r >= R:
        raise ConfigError(f"design {name}: parameter minor={minor!r}, expected less than major={major!r}")
    sweep, arc = _pos(name, "sweep_deg", sweep_deg, hi=360.0), _pos(name, "arc_deg", arc_deg, hi=360.0)
    if sweep > 360 or arc >= 360:
        raise ConfigError(f"design {name}: sweep_deg={sweep_deg!r}, arc_deg={arc_deg!r}, "
                          "expected at most 360 and less than 360")
    nu, nv = _int(name, "nu", nu, 1, MAX_COUNT), _int(name, "nv", nv, 1, MAX_COUNT)
    al = np.radians(np.linspace(-arc / 2, arc / 2, nv + 1))
    profile = np.stack([R + r * np.cos(al), r * np.sin(al)], axis=1)
    m = revolution(profile, nu if sweep == 360 else nu + 1, np.radians(sweep), name=name)
    mesh = _noisy(m, _noise(name, noise), _int(name, "seed", seed, 0, 2 ** 31))
    return Design(name, mesh, 0, "catmull_clark", "circular",
                  f"torus patch {sweep:g} deg x {arc:g} deg, radii {R / 1000:g} / {r / 1000:g} m", p)


def freeform_canopy(*, length: float = 30000.0, width: float = 20000.0, height: float = 2000.0,
                    bumps: int = 2, nu: int = 10, nv: int = 7, levels: int = 2, noise: float = 0.0,
                    seed: int = 0) -> Design:
    """A freeform height-field canopy with seeded bumps, made conical.

    length : extent along x (mm)
    width : extent along y (mm)
    height : mean height of the bumps (mm)
    bumps : number of Gaussian bumps (positions and sizes from seed)
    nu : control quads along x
    nv : control quads along y
    levels : Catmull-Clark rounds
    noise : control-vertex noise, fraction of the mean edge length
    seed : seed of the bumps and the noise
    """
    p = dict(locals())  # the parameters as given
    name = "freeform_canopy"
    L, W, H = (_pos(name, k, p[k]) for k in ("length", "width", "height"))
    k = _int(name, "bumps", bumps, 0, 100)
    seed = _int(name, "seed", seed, 0, 2 ** 31)
    rng = np.random.default_rng(seed)
    cx, cy = rng.uniform(0.2, 0.8, k) * L, rng.uniform(0.25, 0.75, k) * W
    sig = rng.uniform(0.15, 0.3, k) * min(L, W)
    amp = rng.uniform(0.6, 1.4, k) * H

    def lift(X, Y):
        Z = np.zeros_like(X)
        for i in range(k):  # a few bumps
            Z = Z + amp[i] * np.exp(-((X - cx[i]) ** 2 + (Y - cy[i]) ** 2) / (2 * sig[i] ** 2))
        return Z

    m = grid(_int(name, "nu", nu, 2, MAX_COUNT) + 1, _int(name, "nv", nv, 2, MAX_COUNT) + 1, (L, W),
             height=lift, name=name)
    mesh = _noisy(m, _noise(name, noise), seed + 1)
    return Design(name, mesh, _int(name, "levels", levels, 0, 6), "catmull_clark", "conical",
                  f"height-field canopy {L / 1000:g} x {W / 1000:g} m with {k} bumps", p)


DESIGNS = {f.__name__: f for f in (railway_station, trefoil_band, developable_strips, hypar_roof, dome,
                                   torus_patch, freeform_canopy, tunnel)}
"""Design name -> function(**params) -> Design."""


def _param_docs(fn) -> dict[str, str]:
    return dict(re.findall(r"^\s{4}(\w+) : (.+)$", fn.__doc__ or "", flags=re.M))


def describe() -> list[dict]:
    """Every design: name, summary, levels, scheme, target, parameters (name, default, type, help)."""
    out = []
    for name, fn in DESIGNS.items():
        docs = _param_docs(fn)
        d = fn()
        params = [{"name": k, "default": v.default, "type": type(v.default).__name__, "help": docs.get(k, "")}
                  for k, v in inspect.signature(fn).parameters.items()]
        out.append({"name": name, "summary": (fn.__doc__ or "").strip().splitlines()[0],
                    "levels": d.levels, "scheme": d.scheme, "target": d.target, "units": UNITS,
                    "vertices": d.mesh.n_vertices, "faces": d.mesh.n_faces, "params": params})
    return out


def parse_params(name: str, items) -> dict:
    """``["k=v", ...]`` -> typed keyword arguments of design ``name`` (types of the defaults).

    Raises ConfigError naming the design, the key and the expected type.
    """
    if name not in DESIGNS:
        raise ConfigError(f"design {name!r} is unknown, expected one of {sorted(DESIGNS)}")
    sig = inspect.signature(DESIGNS[name]).parameters
    out = {}
    for item in items or []:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep:
            raise ConfigError(f"design {name}: parameter {item!r}, expected key=value")
        if key not in sig:
            raise ConfigError(f"design {name}: unknown parameter {key!r}, expected one of {list(sig)}")
        default = sig[key].default
        try:
            if isinstance(default, bool):
                low = text.strip().lower()
                if low not in ("true", "false", "1", "0", "yes", "no"):
                    raise ValueError(text)
                out[key] = low in ("true", "1", "yes")
            elif isinstance(default, int):
                out[key] = int(text)
            elif isinstance(default, float):
                out[key] = float(text)
            else:
                out[key] = text
        except ValueError:
            raise ConfigError(f"design {name}: parameter {key}={text!r}, expected "
                              f"{type(default).__name__} like the default {default!r}") from None
    return out
