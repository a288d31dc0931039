"""``--units`` of the standalone commands: the length unit of a mesh file, as the config's ``units``.

Every command works and reports in mm (like ``fabricate run``): a mesh read
with ``--units m`` is scaled by 1000 on reading, and a mesh the command writes
as a replacement for its input (optimize, remesh) is scaled back to the
file's unit.
"""
from __future__ import annotations

UNITS = ("mm", "cm", "m", "in", "ft")
UNIT_TO_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "ft": 304.8}  # = fabricate.app.config


def add_units(p, what: str = "the mesh file", default: str | None = "mm") -> None:
    """Add ``--units`` to the subparser ``p``."""
    extra = "" if default else " (default: the design's own units)"
    p.add_argument("--units", choices=UNITS, default=default,
                   help=f"length unit of {what} (default {default or 'none'}{extra}; as the config's "
                        "`units`); every length printed and reported is in mm")


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
