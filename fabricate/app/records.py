"""The typed records that travel between the stages of a run.

Each stage of :mod:`fabricate.app.stages` is a function from the config and the
records of earlier stages to its own record; :func:`fabricate.app.pipeline.run_pipeline`
chains them and collects everything in one :class:`RunRecord`, from which the
report is built (:func:`fabricate.report.write_report`)::

    RunConfig --stage_input-----> InputRecord      mesh (mm), reference surface, plan
              --stage_optimize--> OptimizeRecord   final mesh, OptimizeResult, levels, routes
              --stage_offset----> OffsetRecord     OffsetStructure (layers, node axes, beams)
              --stage_cad-------> PartsRecord      PartSpec, Parts (or why none were built)
              --stage_structure-> StructureRecord  StructureCheck, its report and measures
              --stage_exports---> ExportsRecord    files written, output check
              measures + outcome -> RunRecord ----stage_report--> report.json, pictures, report.html

Records are frozen dataclasses: no stage changes what an earlier one made.  Their
mappings are read-only views (:func:`frozen`) of JSON-ready facts.  The heavy types
(Mesh, OptimizeResult, Parts, ...) are named for the reader only: importing this
module imports none of them.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Mapping

if TYPE_CHECKING:  # pragma: no cover - names for annotations only
    from optimize.mesh import Mesh
    from optimize.result import OptimizeResult

    from ..cad.parts import Parts
    from ..cad.spec import PartSpec
    from .config import RunConfig
    from ..offset.structure import OffsetStructure
    from ..structure.check import StructureCheck

EMPTY: Mapping[str, Any] = MappingProxyType({})


def frozen(mapping: Mapping | None) -> Mapping:
    """A read-only view of a copy of ``mapping`` (``{}`` for None)."""
    return MappingProxyType(dict(mapping or {}))


@dataclass(frozen=True)
class InputRecord:
    """What the input stage read or built.

    mesh : the mesh to subdivide or optimize, in mm.
    surface : the user's triangle surface in mm (the optimizer's reference) for a surface input, else None.
    kind : ``shape`` | ``mesh`` | ``control`` | ``surface``; levels, scheme, target: what the optimize
        stage runs (the design's or the file's defaults, with the config's settings on top).
    facts : report.json's ``input`` (source, units, scale, remesh facts, ...).
    """

    mesh: Mesh
    surface: Mesh | None
    kind: str
    levels: int
    scheme: str
    target: str
    facts: Mapping[str, Any]
    notes: tuple[str, ...] = ()
    line: str = ""
    advice: str = ""  # a mesh file's size that suggests another unit (:func:`fabricate.app.stages.unit_advice`)


@dataclass(frozen=True)
class OptimizeRecord:
    """The optimized mesh and how it came about.

    result : the last level's OptimizeResult (None when nothing was optimized: target none).
    levels : report.json's facts per subdivision level; level_results : their OptimizeResults.
    routes : facts of the routes tried for a user's mesh (:mod:`fabricate.app.decide`), empty otherwise.
    target : the target reached (``pq`` when a user's mesh fell back to it; None: the input's).
    decision : the paragraph that says which route was taken and why ('' for a built-in design).
    """

    mesh: Mesh
    result: OptimizeResult | None
    levels: tuple[Mapping[str, Any], ...] = ()
    level_results: tuple[OptimizeResult | None, ...] = ()
    routes: tuple[Mapping[str, Any], ...] = ()
    notes: tuple[str, ...] = ()
    line: str = ""
    target: str | None = None
    decision: str = ""


@dataclass(frozen=True)
class OffsetRecord:
    """The offset layers, node axes and beam quads (:class:`fabricate.offset.OffsetStructure`)."""

    structure: OffsetStructure
    line: str = ""
    notes: tuple[str, ...] = ()


@dataclass(frozen=True)
class PartsRecord:
    """The parts built from the offset structure with ``spec``, or None and the reason (``skipped``)."""

    spec: PartSpec
    parts: Parts | None
    skipped: str | None = None
    notes: tuple[str, ...] = ()
    line: str = ""


@dataclass(frozen=True)
class StructureRecord:
    """The structural check (``structure.check`` report | enforce), or nothing when off.

    check : the StructureCheck (None when off or skipped); report : report.json's ``structure``
    (None when off); measures : the check's entries for the run's measures (the glass check's too).
    """

    check: StructureCheck | None = None
    report: Mapping[str, Any] | None = None
    measures: Mapping[str, Mapping[str, Any]] = field(default_factory=lambda: EMPTY)
    notes: tuple[str, ...] = ()
    line: str = ""
    glass: Any = None  # the glass check (fabricate.structure.glass.GlassCheck), None when off or skipped


@dataclass(frozen=True)
class ExportsRecord:
    """The files written into the work folder (``{relative name: facts}``) and the output check
    (``{"pass", "mode", "checks", ...}``)."""

    files: Mapping[str, Mapping[str, Any]]
    check: Mapping[str, Any]
    line: str = ""
    cut_batches: Any = None
    """The nested sheets of the cut files (:func:`fabricate.export.cutfiles.nest_cut_files`), which the
    report draws; None when no cut files were written."""


@dataclass(frozen=True)
class Outcome:
    """How a run ends: status (see :data:`fabricate.app.pipeline.PRECEDENCE`), its exit code, the names
    of what failed (measures, ``check:<name>``, ``parts``) and a one-line message naming them."""

    status: str
    exit_code: int
    failed: tuple[str, ...]
    message: str

    def as_dict(self) -> dict[str, Any]:
        return dict(asdict(self), failed=list(self.failed))


@dataclass(frozen=True)
class RunRecord:
    """Everything a finished run made, for the report: the config, the work folder, every stage's
    record, the measures with their requirements applied, the outcome and the timings (s)."""

    config: RunConfig
    workdir: Path
    input: InputRecord
    optimize: OptimizeRecord
    offset: OffsetRecord
    parts: PartsRecord
    structure: StructureRecord
    exports: ExportsRecord
    measures: Mapping[str, Mapping[str, Any]]
    outcome: Outcome
    timings: Mapping[str, float] = field(default_factory=lambda: EMPTY)

    @property
    def notes(self) -> tuple[str, ...]:
        """The stages' notes in run order."""
        return self.input.notes + self.optimize.notes + self.offset.notes + self.parts.notes + self.structure.notes
