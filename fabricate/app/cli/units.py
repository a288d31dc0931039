"""``--units`` of the standalone commands: the length unit of a mesh file, as the config's ``units``.

Every command works and reports in mm (like ``fabricate run``): a mesh read
with ``--units m`` is scaled by 1000 on reading, and a mesh the command writes
as a replacement for its input (optimize, remesh) is scaled back to the
file's unit.  A length option that describes the input's geometry (``remesh
--edge-length``, ``--radius``) is in ``--units`` too, as ``input.edge_length``
is in the config's ``units``; part dimensions (``offset --distances``) are in
mm, as ``offset.distances`` is.  Without ``--units`` (where a command allows
it) a .3dm file is read in its own model unit.
"""
from __future__ import annotations

UNITS = ("mm", "cm", "m", "in", "ft")
UNIT_TO_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "ft": 304.8}  # = fabricate.app.config


def add_units(p, what: str = "the mesh file", default: str | None = "mm") -> None:
    """Add ``--units`` to the subparser ``p`` (``default`` None: the unit a .3dm file states, else mm;
    the command resolves it with :func:`resolve_units`)."""
    said = default or "a .3dm file's model unit, else mm"
    p.add_argument("--units", choices=UNITS, default=default,
                   help=f"length unit of {what} (default {said}; as the config's `units`); every length "
                        "printed and reported is in mm")


def resolve_units(path, units: str | None) -> str:
    """The unit to read ``path`` in: ``units`` (``--units``) when given, else the unit a .3dm file
    states, else mm; prints where it came from when the file states one (a warning when ``--units``
    overrides a different one)."""
    import sys

    from ..config import mesh_file_units

    unit, note, overridden = mesh_file_units(path, units, key="--units")
    if note:
        print(f"{'warning' if overridden else 'note'}: {note}", file=sys.stderr)
    return unit


def length_mm(value: float, units: str) -> float:
    """A length given on the command line in ``units``, in mm."""
    return value * UNIT_TO_MM[units]


def positive_length(text: str) -> float:
    """argparse type: a finite length > 0."""
    import argparse
    import math

    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r}: expected a length > 0 (a finite number in --units)")
    return value


def read_mm(path, units: str):
    """The mesh in ``path`` with its vertices in mm (``units`` is the file's unit)."""
    from optimize.mesh.io import read_mesh

    mesh = read_mesh(path)
    f = UNIT_TO_MM[units]
    return mesh if f == 1.0 else mesh.with_vertices(mesh.V * f)


def to_file_units(mesh, units: str):
    """``mesh`` (mm) with its vertices in ``units``, for writing beside the user's input."""
    f = UNIT_TO_MM[units]
    return mesh if f == 1.0 else mesh.with_vertices(mesh.V / f)


def mm(x: float) -> str:
    """A length in mm for people: ``0.0202 mm``, ``12.5 mm``, ``1,250 mm``."""
    ax = abs(x)
    if ax >= 1000:
        return f"{x:,.0f} mm"
    return f"{x:.3g} mm"
