"""Checking the parameters of a built-in design in a config, in bounded time and memory.

``input.shape: {name, params}`` names a function of :mod:`optimize.modelling.designs`.
:func:`check_design` checks, before anything is built:

- the name and every parameter name (with a did-you-mean);
- every parameter's type against its default's: an integer parameter takes
  integers (not ``true``, not ``2.5``), a number parameter finite numbers, a
  flag ``true`` / ``false``, a word a string;

then builds the control mesh, which the design's own ranges keep small
(every count has an upper bound there: ``nu <= 500``, ``meridians <= 1000``,
...; every length is at most :data:`optimize.modelling.designs.MAX_SIZE_MM`), turning
any arithmetic failure into a ConfigError, and returns the design.
:func:`subdivided_faces` then bounds what the subdivision will make of it
(``fabricate.app.config`` and ``fabricate shapes --refined`` refuse more than
:data:`MAX_FACES`).
"""
from __future__ import annotations

import inspect
import math
from typing import Any

import numpy as np

from optimize.errors import ConfigError

from .config_errors import did_you_mean, short

MAX_FACES = 250_000
"""Most faces a built-in design may have after subdivision (the message names this limit)."""

GROWTH = {"catmull_clark": 4, "doo_sabin": 4, "chaikin": 2, "lane_riesenfeld": 2}
"""Faces per face and subdivision round (Doo-Sabin adds vertex and edge faces: about 4 on quads)."""


class DesignParamError(ConfigError):
    """A design parameter that is wrong; ``key`` names it (for the line in the message)."""

    def __init__(self, message: str, key: str | None = None):
        super().__init__(message)
        self.key = key


def _kind(default: Any) -> str:
    if isinstance(default, bool):
        return "flag"
    if isinstance(default, int):
        return "integer"
    if isinstance(default, float):
        return "number"
    return "word"


def _type_ok(kind: str, value: Any) -> bool:
    if kind == "flag":
        return isinstance(value, bool)
    if kind == "integer":
        return isinstance(value, int) and not isinstance(value, bool)
    if kind == "number":
        return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    return isinstance(value, str)


EXPECT = {"flag": "true or false", "integer": "an integer", "number": "a finite number", "word": "a string"}


def check_design(name: Any, params: dict[str, Any]):
    """The :class:`optimize.modelling.designs.Design` of ``name(**params)``, checked (see the module docstring).

    Raises DesignParamError naming the parameter, the value and what is expected.
    """
    from optimize.modelling.designs import DESIGNS

    if not isinstance(name, str) or name not in DESIGNS:
        raise DesignParamError(f"unknown design {short(name)}{did_you_mean(name, DESIGNS)} "
                               f"(allowed: {', '.join(sorted(DESIGNS))})")
    fn = DESIGNS[name]
    sig = inspect.signature(fn).parameters
    allowed = [k for k, p in sig.items() if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
    for key, value in params.items():
        if key not in allowed:
            raise DesignParamError(f"unknown parameter {short(key)}{did_you_mean(key, allowed)} "
                                   f"(allowed: {', '.join(allowed) or 'none'})", str(key))
        kind = _kind(sig[key].default)
        if not _type_ok(kind, value):
            raise DesignParamError(f"design {name}: parameter {key}={short(value)}, expected {EXPECT[kind]} "
                                   f"(like the default {sig[key].default!r})", key)
    try:
        with np.errstate(all="ignore"):  # a design that overflows is caught by the finite check below
            design = fn(**params)
    except ConfigError as exc:
        raise DesignParamError(str(exc), _named_param(str(exc), params)) from None
    except (ArithmeticError, ValueError, TypeError, np.linalg.LinAlgError) as exc:
        raise DesignParamError(f"design {name}: parameters {short(params)} do not make a mesh "
                               f"({type(exc).__name__}: {short(str(exc))}); expected values nearer the "
                               "defaults (fabricate shapes lists them)") from None
    V = design.mesh.V
    if not np.isfinite(V).all():
        raise DesignParamError(f"design {name}: parameters {short(params)} give vertices that are not finite; "
                               "expected values nearer the defaults (fabricate shapes lists them)")
    return design


def _named_param(message: str, params: dict[str, Any]) -> str | None:
    return next((k for k in params if f"parameter {k}=" in message or f" {k}=" in message), None)


def subdivided_faces(faces: int, scheme: str, levels: int) -> int:
    """Faces after ``levels`` rounds of ``scheme`` on a mesh of ``faces`` faces (an upper estimate)."""
    return int(faces) * GROWTH.get(scheme, 4) ** int(levels)
