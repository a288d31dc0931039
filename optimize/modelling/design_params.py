"""What every built-in design is made of: the :class:`Design` record and the checks of its
parameters (each names the design, the key, the value and the range), shared by
:mod:`optimize.modelling.designs` and :mod:`optimize.modelling.design_tunnel`."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError
from ..mesh import Mesh
from .shapes import perturbed

UNITS = "mm"


@dataclass(frozen=True)
class Design:
    """A built-in design.

    name : str
    mesh : Mesh, the starting mesh in mm (control mesh when ``levels > 0``).
    levels : int, rounds of subdivide-and-perturb.
    scheme : str, subdivision scheme (``optimize.modelling.subdivision.SCHEMES``).
    target : str, ``"pq"`` | ``"conical"`` | ``"circular"`` | ``"strip"``.
    description : str, one sentence.
    params : dict, every parameter as used (defaults filled in).
    """

    name: str
    mesh: Mesh
    levels: int
    scheme: str
    target: str
    description: str
    params: dict = field(default_factory=dict)
    units: str = UNITS


# -- parameter checks ----------------------------------------------------------------

def int_param(design: str, key: str, value, lo: int, hi: int) -> int:
    """An integer in ``lo..hi``; ConfigError naming the design, the key and the range."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not lo <= value <= hi:
        raise ConfigError(f"design {design}: parameter {key}={value!r}, expected an integer in {lo}..{hi}")
    return int(value)


MAX_SIZE_MM = 1e6
"""Largest length parameter of a design (1 km): beyond it the numbers mean a mistake, not a roof."""
MAX_NOISE = 1.0
"""Largest ``noise`` (a fraction of the mean edge length)."""
MAX_COUNT = 300
"""Largest quad count along one direction of a design (300 x 300 = 90,000 quads, built in well
under a second): the counts are bounded so that checking a config, which builds the design, stays
cheap; the subdivided size is bounded by the config (``fabricate.app.config.MAX_FACES``)."""


def pos_param(design: str, key: str, value, zero: bool = False, hi: float = MAX_SIZE_MM) -> float:
    """A finite number in ``(0, hi]`` (``[0, hi]`` with ``zero``); ConfigError naming the range."""
    ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool) \
        and bool(np.isfinite(value)) and (value >= 0 if zero else value > 0) and value <= hi
    if not ok:
        top = f"{hi:g}".replace("e+0", "e").replace("e+", "e")
        raise ConfigError(f"design {design}: parameter {key}={value!r}, expected a number in "
                          f"{'[0' if zero else '(0'}, {top}]")
    return float(value)


def noise_param(design: str, value) -> float:
    """The ``noise`` parameter: a fraction of the mean edge in ``[0, MAX_NOISE]``."""
    return pos_param(design, "noise", value, zero=True, hi=MAX_NOISE)


def noisy(mesh: Mesh, noise: float, seed: int) -> Mesh:
    """``mesh`` shaken by ``noise`` (seeded), or ``mesh`` itself without noise."""
    return perturbed(mesh, noise, seed=seed, name=mesh.name) if noise > 0 else mesh
