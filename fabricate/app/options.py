"""The one source of the application's defaults: frozen option objects.

Each class is a frozen dataclass whose fields carry their default, their
bounds, unit and help in the field metadata (:func:`fabricate.fields.option`).  The config
sections of :mod:`fabricate.app.config` are derived from them
(:func:`fabricate.app.config_section.section_base`), and the command line reads
its defaults from them, so every default is written once.  This module imports
no pydantic and nothing heavy (``fabricate --help`` reads it).

- :class:`OffsetOptions`   the ``offset`` section;
- :class:`OutputsOptions`  the ``outputs`` section (which files, the check);
- :data:`TOLERANCE_KEYS`   bounds and units of the ``tolerances`` section, whose defaults are
  :class:`optimize.tolerances.Tolerances`' (the one tolerance object);
- :class:`RunOptions`      the top-level keys of a run config (name, units, scale);
- :class:`CommandOptions`  what ``fabricate run`` / ``batch`` take on the command line.

The options of a stage live with the stage: ``parts`` in :class:`fabricate.cad.spec.PartSpec`,
``structure`` in :class:`fabricate.structure.options.StructureOptions`; their sections are derived
the same way (:mod:`fabricate.app.config_parts`, :mod:`fabricate.app.config_structure`).

The optimizer's section stays as it is until ``optimize`` has its own frozen options.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from ..fields import MAX_MM, option  # also re-exported

CHECK_AUTO_MAX_PARTS = 25000
"""``outputs.check: auto`` runs the full check up to this many parts, the fast one above: the full
check costs less than the export it checks on every model measured (``benchmarks/bench_cad.py
--check`` and ``--sections``: up to 19,215 parts), and its memory grows with the STEP file (the
reader holds every record: about 1 GB for a 165 MB file of 15,100 parts)."""

UNIT_TO_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "ft": 304.8}
"""Millimetres per unit of ``units``."""


@dataclass(frozen=True)
class OffsetOptions:
    """The offset layers."""

    distances: tuple[float, ...] | None = option(
        None, unit="mm", min_length=2, max_length=32, items=dict(ge=-MAX_MM, le=MAX_MM),
        help="layer distances, signed along the face normals; null: [0, -parts.beam_depth]")
    flip: bool = option(False, help="reverse the face normals (offset to the other side)")


@dataclass(frozen=True)
class OutputsOptions:
    """Which files a run writes (report.json always), and how they are checked.

    ``flat``, ``cut_files`` and ``layout_plan`` follow ``dxf`` and ``schedules`` follows ``bom`` when
    None.  ``check``: ``full`` (every check, model.step read back by the independent text reader),
    ``fast`` (the same without the STEP read-back), ``off``, or ``auto`` (full up to
    :data:`CHECK_AUTO_MAX_PARTS` parts, fast above)."""

    mesh: bool = option(True, help="mesh.obj, the optimized mesh (mm)")
    layers: bool = option(True, help="layer_<i>.obj, the offset layers")
    step: bool = option(True, help="model.step")
    stl: bool = option(True, help="model.stl")
    three_mf: bool = option(True, alias="3mf", help="model.3mf")
    dxf: bool = option(True, help="outlines.dxf, the flat outlines")
    svg: bool = option(True, help="outlines.svg")
    flat: bool | None = option(None, help="flat.json (null: as dxf)")
    schedules: bool | None = option(None, help="glass, steel and node schedules (null: as bom)")
    glass_order: bool = option(True, help="glass_order.csv and glass_order/: positions, R12 drawings, labels")
    cut_files: bool | None = option(None, help="nested cut files per material and thickness (null: as dxf)")
    stl_parts: bool = option(False, help="one STL per part in stl/")
    layout_plan: bool | None = option(None, help="layout_plan.dxf with the part ids (null: as dxf)")
    bom: bool = option(True, help="bom.csv, the bill of materials every check compares with")
    ifc: bool = option(True, help="model.ifc (IFC4)")
    rhino: bool = option(True, alias="3dm", help="model.3dm (Rhino)")
    nc1: bool = option(True, help="nc1/, DSTV NC1 files for steel CNC")
    gltf: bool = option(True, help="parts.glb")
    step_schema: Literal["AP214", "AP242"] = option("AP214", help="STEP application protocol")
    pictures: bool = option(True, help="the PNG pictures")
    html: bool = option(True, help="report.html with the 3D view")
    check: Literal["auto", "full", "fast", "off"] = option("auto", help="how the written files are re-validated")
    overwrite: bool = option(False, help="replace an earlier finished run (as fabricate run --force)")


TOLERANCE_KEYS = {
    # relative and angular tolerances: 1e-12 is about what double precision can show; 1 is no test
    "planarity": dict(ge=1e-12, le=1.0, unit="relative", help="diagonal distance / mean diagonal"),
    "conical": dict(ge=1e-12, le=1.0, unit="rad", help="|w1 + w3 - w2 - w4| at interior valence-4 vertices"),
    "circular": dict(ge=1e-12, le=1.0, unit="rad", help="max(|phi1 + phi3 - pi|, |phi2 + phi4 - pi|) per quad"),
    "offset": dict(ge=1e-12, le=1.0, unit="relative", help="offset face distance error / offset distance"),
    "beam_planarity": dict(ge=1e-12, le=1.0, unit="relative", help="planarity of the beam quads"),
    "cad_linear_mm": dict(ge=1e-7, le=1.0, unit="mm", help="OpenCASCADE's modelling tolerance (1e-7 mm at least)"),
    "closeness": dict(ge=1e-12, le=1.0, unit="relative", help="distance to the reference / bbox diagonal"),
    "closeness_mm": dict(ge=1e-6, le=1e6, unit="mm", help="how far the design may move (makes closeness a "
                         "requirement; null: reported only)"),
    "roughness": dict(ge=1.0, le=1e6, unit="ratio", help="roughness of the result / of the input beyond which "
                      "a warning is given"),
    "beam_twist_mm": dict(ge=1e-9, le=1000.0, unit="mm", help="largest twist of a beam a steel shop takes"),
    "fold": dict(ge=1e-12, le=1.0, unit="sine", help="a convex corner whose signed sine ends below -fold is dented"),
    "strip_parallel": dict(ge=1e-12, le=1.0, unit="sine", help="rulings of a strip closer than this are parallel"),
    "file_volume": dict(ge=1e-12, le=1.0, unit="relative", help="solid volumes read back from the files / BOM"),
    "file_area": dict(ge=1e-12, le=1.0, unit="relative", help="cut outline areas read back / flat data"),
    "file_edge_mm": dict(ge=1e-9, le=1.0, unit="mm", help="cut outline edge lengths read back / flat data"),
}
"""Bounds, units and help of the ``tolerances`` keys; their defaults are those of
:class:`optimize.tolerances.Tolerances`."""


@dataclass(frozen=True)
class RunOptions:
    """The top-level keys of a run config besides its sections."""

    name: str | None = option(None, pattern=r"^[A-Za-z0-9][A-Za-z0-9_.=+-]*$", max_length=120,
                              help="the run folder's name (null: the config file's name)")
    units: Literal["mm", "cm", "m", "in", "ft"] = option("mm", help="units of the input mesh file")
    scale: float = option(1.0, ge=1e-6, le=1e6, help="factor applied to the input (after units)")


@dataclass(frozen=True)
class CommandOptions:
    """Defaults of ``fabricate run`` and ``fabricate batch`` (command line only, not config keys)."""

    out_root: str = option("outputs", help="parent folder of the run folders")
    workers: int | None = option(None, ge=1, help="parallel worker processes (null: one per core, at most one "
                                                  "per job)")
    connect_timeout_s: float = option(20.0, gt=0, unit="s", help="seconds to reach a dask scheduler")


COMMAND = CommandOptions()
"""The command line's defaults."""
