"""Run configurations: YAML files validated by a pydantic schema.

A config names the input (a built-in design, a mesh file, a control mesh or a
triangle surface), the subdivision and optimization settings, the tolerances,
the offset layers and part dimensions (mm), the files to write and the units
of the input.  ``configs/reference.yaml`` lists every key with its default.

Every mistake is a :class:`optimize.errors.ConfigError` whose message names the
file and line, the key path, the value and what is allowed, with a
did-you-mean for misspelt keys::

    configs/dome.yaml:7: optimize.targte: unknown key (did you mean 'target'?); allowed: ...

Files are read by :mod:`fabricate.app.config_yaml` (safe YAML, bounded in size,
nesting and alias expansion, duplicate keys refused); paths in a config are
resolved relative to the config file's folder.

Types are strict: ``true`` is not a number, ``.inf`` / ``.nan`` are refused
everywhere (no key takes them), an integer key takes integers only.  Every
value with a physical meaning has a range (``configs/reference.yaml`` lists
them); the message of a value outside it names the range.  YAML reads ``off``,
``no``, ``on``, ``yes`` as booleans: a key whose allowed words include them
(``outputs.check: off``) takes the boolean as that word.

``--set KEY=VALUE`` values (:func:`override_values`): a comma list given to a
key that takes a list is that list (``offset.distances=0,-200`` is
``[0, -200]``); for any other key the commas separate the values of a sweep,
which only ``fabricate batch`` runs (``fabricate batch --set
offset.distances=[0,-200],[0,-300]`` sweeps two lists).
"""
from __future__ import annotations

import dataclasses
import logging
import math
import re
from pathlib import Path
from typing import Any, Literal

from pydantic import (Field, PrivateAttr, ValidationError, ValidationInfo,
                      field_validator, model_validator)
from pydantic_core import PydanticCustomError

import optimize.options as OPT
from optimize.errors import ConfigError
from optimize.tolerances import Tolerances

from .config_design import MAX_FACES, DesignParamError, check_design, subdivided_faces
from .config_errors import format_errors
from .config_parts import (BarsSection, GasketSection, LimitsSection, NestingSection,  # noqa: F401 - re-exported
                           PartsSection, SheetSection)
from .config_section import MAX_MM, Section, section_base, tuples  # noqa: F401 - MAX_MM re-exported
from . import config_set
from .config_set import set_key  # noqa: F401 - the --set API, re-exported
from .config_structure import StructureSection
from .config_yaml import MAX_DEPTH, read_config
from .options import (CHECK_AUTO_MAX_PARTS, TOLERANCE_KEYS, UNIT_TO_MM, OffsetOptions,  # noqa: F401 - re-exported
                      OutputsOptions, RunOptions)

INPUT_KINDS = ("shape", "mesh", "control", "surface")

log = logging.getLogger(__name__)


MAX_ITER = OPT.MAX_ITER
"""Largest ``optimize.max_iter`` (:data:`optimize.options.MAX_ITER`)."""


def _resolve_path(value: Any, info: ValidationInfo) -> Path | None:
    """A path relative to the config file's folder; the file must exist."""
    if value is None:
        return None
    if not isinstance(value, (str, Path)) or not str(value).strip() or "\0" in str(value):
        raise PydanticCustomError("path", "expected a file path (a string)")
    if len(str(value)) > 1024:
        raise PydanticCustomError("path", "expected a file path of at most 1024 characters")
    base = Path((info.context or {}).get("base_dir", "."))
    try:
        path = Path(value).expanduser()
        full = (path if path.is_absolute() else base / path).resolve()
        found, exists = full.is_file(), full.exists()
    except (OSError, RuntimeError) as exc:  # a name too long, a symlink loop, no home folder
        raise PydanticCustomError("path", "cannot use this path ({err})",
                                  {"err": getattr(exc, "strerror", None) or str(exc)}) from None
    if not found and exists:
        what = "a folder" if full.is_dir() else "not a regular file (a device, a pipe, ...)"
        raise PydanticCustomError("path_kind", "{full} is {what}; expected a mesh file",
                                  {"full": str(full), "what": what})
    if not found:
        raise PydanticCustomError("path_missing", "file not found: {full} (resolved relative to {base})",
                                  {"full": str(full), "base": str(base.resolve())})
    return full


class ShapeInput(Section):
    """A built-in design of :mod:`optimize.modelling.designs` with its parameters (checked by
    :func:`fabricate.app.config_design.check_design`)."""

    name: str
    params: dict[str, Any] = Field(default_factory=dict)

    _design: Any = PrivateAttr(default=None)

    @model_validator(mode="after")
    def _known_design(self) -> "ShapeInput":
        try:
            design = check_design(self.name, self.params)
        except DesignParamError as exc:
            ctx = {"err": str(exc), **({"param": exc.key} if exc.key else {})}  # the param's line
            raise PydanticCustomError("design_value", "{err}", ctx) from None
        except ImportError as exc:  # the modelling package is not installed
            raise PydanticCustomError("designs", "built-in designs are not available ({err})",
                                      {"err": str(exc)}) from None
        self._design = design  # built once: the input stage uses this one
        return self

    @property
    def design(self):
        """The :class:`optimize.modelling.designs.Design` built while validating (the input stage's mesh)."""
        return self._design


class InputSection(Section):
    """Exactly one of ``shape``, ``mesh``, ``control`` or ``surface``."""

    shape: ShapeInput | None = None
    mesh: Path | None = None
    control: Path | None = None
    surface: Path | None = None
    edge_length: float | None = Field(default=None, gt=0, le=1e7)
    irregular: Literal["faces", "vertices", "nearest"] | None = None
    side: Literal["keep"] | tuple[float, float, float] | None = None
    radius: float | None = Field(default=None, gt=0, le=1e7)
    remesh: Literal["auto", "always", "never"] | None = None  # None: auto for a mesh input
    layer: str | None = Field(default=None, min_length=1, max_length=500)
    object: str | None = Field(default=None, min_length=1, max_length=500)

    _paths = field_validator("mesh", "control", "surface", mode="before")(_resolve_path)

    _side_list = tuples("side")

    @field_validator("layer", "object", mode="before")
    @classmethod
    def _number_as_name(cls, v):  # a layer or object named `12` is a name
        return str(v) if isinstance(v, int) and not isinstance(v, bool) else v

    @model_validator(mode="after")
    def _exactly_one(self) -> "InputSection":
        given = [k for k in INPUT_KINDS if getattr(self, k) is not None]
        if len(given) != 1:
            found = ", ".join(given) if given else "none"
            raise PydanticCustomError("input_kind", "give exactly one of shape, mesh, control, surface "
                                      "(found: {found})", {"found": found})
        if self.surface is not None and self.edge_length is None:
            raise PydanticCustomError("edge_length", "a surface input needs edge_length (target quad "
                                      "edge length in the input's units)")
        if self.surface is None and self.edge_length is not None:
            raise PydanticCustomError("edge_length", "edge_length applies only to a surface input")
        if self.surface is None and self.irregular is not None:
            raise PydanticCustomError("irregular", "irregular applies only to a surface input")
        if self.surface is None and self.side is not None:
            raise PydanticCustomError("side", "side applies only to a surface input")
        if self.mesh is None and self.remesh not in (None, "never"):
            raise PydanticCustomError("remesh", "remesh applies only to a mesh input (a surface input is "
                                      "remeshed anyway)")
        rhino = self.mesh is not None and self.mesh.suffix.lower() == ".3dm"
        for key in ("layer", "object"):
            if getattr(self, key) is not None and not rhino:
                raise PydanticCustomError(key, "{key} picks a mesh in a .3dm file given as input.mesh",
                                          {"key": key})
        if self.surface is None and self.radius is not None:
            raise PydanticCustomError("radius", "radius applies only to a surface input")
        if isinstance(self.side, tuple) and not 0 < sum(c * c for c in self.side) < math.inf:
            raise PydanticCustomError("side", "side {side} is not a nonzero vector of finite length, expected "
                                      "[x, y, z] toward the inside or 'keep'", {"side": list(self.side)})
        return self

    @property
    def kind(self) -> str:
        return next(k for k in INPUT_KINDS if getattr(self, k) is not None)


class SubdivisionSection(Section):
    """``null`` means: the built-in design's own (else catmull_clark, 2 levels for a control mesh,
    0 otherwise); chaikin and lane_riesenfeld refine developable strips."""

    scheme: Literal["catmull_clark", "doo_sabin", "chaikin", "lane_riesenfeld"] | None = None
    levels: int | None = Field(default=None, ge=0, le=6)  # Catmull-Clark: 4^6 = 4096 faces per face


_OPTIMIZE_KEYS = ["target", "method", "formulation", "linear_solver", "torsion_free_beams", "fairness", "closeness",
                  "max_iter", "fixed", "glide_boundary", "convex", "refine", "rationalize"]


class OptimizeSection(section_base(OPT.OptimizeOptions, order=_OPTIMIZE_KEYS, extra={
        "target": (Literal[OPT.TARGETS + ("none",)] | None, Field(default=None)),
        "fixed": (Literal["boundary", "corners"] | list[int] | None, Field(default=None))})):
    """The optimizer's settings: defaults, choices and bounds are the fields of
    :class:`optimize.options.OptimizeOptions` (one place; ``tol`` is the tolerances section); of the
    section only: ``target: null`` the input's own, ``none`` no optimization, and the ``fixed`` vertices."""

    @field_validator("fixed")
    @classmethod
    def _indices(cls, v):
        bad = [i for i in v if not 0 <= i < 2 ** 31] if isinstance(v, list) else []
        if bad:  # whether an index is below the vertex count is checked once the mesh is read
            raise PydanticCustomError("fixed", "vertex index {i}: vertex indices must be >= 0 and below 2^31",
                                      {"i": bad[0]})
        return v


MEASURE_NAMES = ("planarity", "folded", "conical", "circular", "closeness", "offset_distance", "beam_planarity",
                 "beam_planarity_boundary", "beam_twist", "axis_defect")
"""What ``tolerances.requirements`` may name (``fabricate.app.requirements.MEASURES``)."""


class TolerancesSection(section_base(Tolerances, meta=TOLERANCE_KEYS)):
    """Thresholds (see :class:`optimize.tolerances.Tolerances`, their defaults): relative, radians, or mm;
    bounds in :data:`fabricate.app.options.TOLERANCE_KEYS`."""

    requirements: list[Literal[MEASURE_NAMES]] | None = None

    def to_tolerances(self) -> Tolerances:
        return self.to_options()


class OffsetSection(section_base(OffsetOptions)):
    """Layer distances in mm (signed, along the face normals); ``null``: ``[0, -beam_depth]``
    (defaults and bounds: :class:`fabricate.app.options.OffsetOptions`)."""

    @field_validator("distances")
    @classmethod
    def _distinct(cls, v):
        if v is not None and len(set(v)) != len(v):
            raise PydanticCustomError("distances", "layer distances must be distinct")
        return v


_OUTPUT_KEYS = [f.name for f in dataclasses.fields(OutputsOptions)]


class OutputsSection(section_base(OutputsOptions, extra={
        "nesting": (NestingSection, Field(default_factory=NestingSection)),
        "bars": (BarsSection, Field(default_factory=BarsSection)),
        "gasket": (GasketSection, Field(default_factory=GasketSection))},
        order=_OUTPUT_KEYS[:_OUTPUT_KEYS.index("layout_plan") + 1] + ["nesting", "bars", "gasket"]
        + _OUTPUT_KEYS[_OUTPUT_KEYS.index("layout_plan") + 1:])):
    """Which files to write (``true``/``false``); report.json is always written (defaults and
    what each key means: :class:`fabricate.app.options.OutputsOptions`).

    ``check``: how the written files are re-validated (``fabricate.check``):
    ``full`` (every check, model.step read back by the independent text reader),
    ``fast`` (the same without the STEP read-back), ``off``, or
    ``auto`` (full up to :data:`CHECK_AUTO_MAX_PARTS` parts, fast above).
    """

    def wanted(self, key: str) -> bool:
        """Whether the file of ``key`` is written: ``flat``, ``cut_files`` and ``layout_plan`` follow
        ``dxf`` and ``schedules`` follows ``bom`` unless set."""
        value = getattr(self, key)
        if value is None:
            return bool(getattr(self, {"flat": "dxf", "schedules": "bom", "cut_files": "dxf",
                                       "layout_plan": "dxf"}[key]))
        return bool(value)

    def check_mode(self, parts: int) -> str:
        """``full`` | ``fast`` | ``off`` for a model of ``parts`` parts (``auto`` resolved)."""
        if self.check != "auto":
            return self.check
        return "full" if parts <= CHECK_AUTO_MAX_PARTS else "fast"


_SECTIONS = {
    "input": (InputSection, ...),
    "subdivision": (SubdivisionSection, Field(default_factory=SubdivisionSection)),
    "optimize": (OptimizeSection, Field(default_factory=OptimizeSection)),
    "tolerances": (TolerancesSection, Field(default_factory=TolerancesSection)),
    "offset": (OffsetSection, Field(default_factory=OffsetSection)),
    "parts": (PartsSection, Field(default_factory=PartsSection)),
    "outputs": (OutputsSection, Field(default_factory=OutputsSection)),
    "structure": (StructureSection, Field(default_factory=StructureSection)),
}


class RunConfig(section_base(RunOptions, extra=_SECTIONS, order=["name", *_SECTIONS, "units", "scale"])):
    """A whole run configuration (one YAML file): the sections and the keys of
    :class:`fabricate.app.options.RunOptions`."""

    _source: Path | None = PrivateAttr(default=None)
    _units_note: str | None = PrivateAttr(default=None)

    @field_validator("name", mode="before")
    @classmethod
    def _number_name(cls, v):  # `name: 2024` names a folder too
        return str(v) if isinstance(v, int) and not isinstance(v, bool) else v

    @property
    def source(self) -> Path | None:
        """The config file this came from (None for a dict)."""
        return self._source

    @property
    def units_note(self) -> str | None:
        """Where ``units`` came from when the input file states its own unit (a .3dm file): taken from
        the file, or the config's overriding a different one (also logged as a warning); else None."""
        return self._units_note

    @property
    def mm_per_unit(self) -> float:
        """Factor from input units to millimetres (``units`` times ``scale``)."""
        return UNIT_TO_MM[self.units] * self.scale

    def layer_distances(self) -> list[float]:
        """The offset distances in mm (default ``[0, -beam_depth]``: beams behind the glass)."""
        d = self.offset.distances
        return list(d) if d is not None else [0.0, -self.parts.beam_depth]

    def as_dict(self) -> dict[str, Any]:
        """JSON/YAML-ready dict of the config as run (paths absolute, defaults filled)."""
        return self.model_dump(mode="json", by_alias=True)


def takes_list(dotted: str) -> bool:
    """Whether the config key ``dotted`` (``offset.distances``) takes a list of values."""
    return config_set.takes_list(dotted, RunConfig)


def override_values(key: str, texts: list[str]) -> list[Any]:
    """The values of ``--set key=a,b,...`` for a run config (:func:`fabricate.app.config_set.override_values`)."""
    return config_set.override_values(key, texts, RunConfig)


# -- loading ---------------------------------------------------------------
def load_config(path: str | Path, overrides: dict[str, Any] | None = None) -> RunConfig:
    """Read and validate a YAML config file (read by :func:`fabricate.app.config_yaml.read_config`).

    overrides : ``{"parts.glass_thickness": 8, ...}`` applied to the YAML data
        before validation (the ``--set`` of ``fabricate run`` / ``batch``).

    Raises ConfigError naming the file, line, key path, value and what is allowed.
    """
    path = Path(path)
    data, lines = read_config(path)
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping of sections (name, input, ...), "
                          f"found {type(data).__name__}")
    return parse_config(data, source=path, overrides=overrides, lines=lines)


def parse_config(data: dict[str, Any], *, source: str | Path = "<config>", base_dir: str | Path | None = None,
                 overrides: dict[str, Any] | None = None, lines: dict[tuple, int] | None = None) -> RunConfig:
    """Validate a config dict (``source`` names it in messages; paths relative to ``base_dir``,
    default the folder of ``source``)."""
    source = Path(source)
    base = Path(base_dir) if base_dir is not None else source.parent
    data = _copy(data, source)
    for key, value in (overrides or {}).items():
        set_key(data, key, _copy(value, source), source=source)
    try:
        cfg = RunConfig.model_validate(data, context={"base_dir": base})
    except ValidationError as exc:
        raise ConfigError(format_errors(exc, source, lines or {}, overrides or {}, RunConfig, data)) from None
    if cfg.name is None:
        cfg.name = _safe_name(source.stem)
    cfg._source = source
    _cross_checks(cfg, source, lines or {})
    _file_units(cfg, source, lines or {})
    return cfg


def mesh_file_units(path: str | Path, given: str | None, *, scale: float = 1.0,
                    key: str = "units") -> tuple[str, str | None, bool]:
    """``(unit, note, overridden)``: the unit to read the mesh file ``path`` in.

    ``given`` (the config's ``units`` or ``--units``; None when not given) wins; without it, the
    unit the file states (a .3dm file's model unit, :func:`optimize.mesh.io.api.mesh_units`), else
    mm.  ``note`` says where the unit came from when the file states one; ``overridden`` is True
    when ``given`` (times ``scale``) differs from the file's unit (the caller warns).  A file in a
    unit ``key`` does not name (Kilometers, Yards) and no ``given``: ConfigError naming the unit.
    """
    from optimize.mesh.io.api import mesh_units

    stated = mesh_units(path)
    if stated is None:
        return given or "mm", None, False
    name, mm = stated
    if mm is None:
        unit = given or "mm"
        return unit, f"{path}: the file states no model unit ({name}); read in {unit}", False
    found = next((u for u, f in UNIT_TO_MM.items() if math.isclose(f, mm, rel_tol=1e-12)), None)
    if given is None:
        if found is None:
            raise ConfigError(f"{path}: the file's model unit is {name} ({mm:g} mm), which {key} has no name for; "
                              f"expected {key} set to one of {', '.join(UNIT_TO_MM)} (with scale for the rest, e.g. "
                              f"units: m and scale: {mm / 1000:g} for {name})")
        return found, f"{path}: read in {found}, the file's model unit ({name}); {key} not given", False
    if not math.isclose(UNIT_TO_MM[given] * scale, mm, rel_tol=1e-12):
        return given, (f"{path}: {key} {given}" + (f" x {scale:g}" if scale != 1.0 else "") + f" overrides the "
                       f"file's model unit {name} ({mm:g} mm): its coordinates are read as {given}"), True
    return given, f"{path}: read in {given}, as the file's model unit ({name}) says", False


def _file_units(cfg: RunConfig, source: Path, lines: dict[tuple, int]) -> None:
    """``units`` of an input file that states its own unit (a .3dm): the file's when the config gives
    none (said in :attr:`RunConfig.units_note` and the log), the config's otherwise (a warning when
    they differ)."""
    if cfg.input.kind == "shape":
        return
    path = getattr(cfg.input, cfg.input.kind)
    given = cfg.units if "units" in cfg.model_fields_set else None
    try:
        unit, note, overridden = mesh_file_units(path, given, scale=cfg.scale)
    except ConfigError as exc:
        raise ConfigError(f"{_at(source, lines, ('input', cfg.input.kind))}: input.{cfg.input.kind}: {exc}") from None
    if note is None:
        return
    cfg.units, cfg._units_note = unit, note
    (log.warning if overridden else log.info)("%s", note)


def _at(source: Path, lines: dict[tuple, int], *keys: tuple) -> str:
    line = next((lines[k] for k in keys if k in lines), None)
    return f"{source}:{line}" if line else str(source)


def _cross_checks(cfg: RunConfig, source: Path, lines: dict[tuple, int]) -> None:
    if cfg.input.shape is not None and "units" in cfg.model_fields_set and cfg.units != "mm":
        raise ConfigError(f"{_at(source, lines, ('units',))}: units: {cfg.units!r} applies to mesh files; "
                          "built-in designs are in mm (their sizes are parameters); expected mm or no units key "
                          "(scale still applies)")
    shape = cfg.input.shape
    if shape is not None:
        design = shape.design
        levels = design.levels if cfg.subdivision.levels is None else cfg.subdivision.levels
        scheme = cfg.subdivision.scheme or design.scheme
        faces = subdivided_faces(design.mesh.n_faces, scheme, levels)
        if faces > MAX_FACES:
            where = _at(source, lines, ("subdivision", "levels"), ("input", "shape"))
            raise ConfigError(f"{where}: input.shape: design {shape.name} has {design.mesh.n_faces:,} faces; {levels} "
                              f"rounds of {scheme} make about {faces:,}, more than {MAX_FACES:,} (the largest "
                              "design run); expected fewer quads (the design's count parameters) or fewer "
                              "subdivision.levels")
    try:  # the rules that join several keys (the joint gap below the bearing width, flange vs web, hub radius)
        cfg.parts.to_options()
    except ConfigError as exc:  # the line of the first key the message names that the file has
        keys = [tuple(k.split(".")) for k in re.findall(r"\bparts(?:\.\w+)+", str(exc))]
        raise ConfigError(f"{_at(source, lines, *keys, ('parts',))}: {exc}") from None
    if cfg.offset.distances is not None and "beam_depth" in cfg.parts.model_fields_set:
        span = abs(cfg.offset.distances[-1] - cfg.offset.distances[0])
        if abs(span - cfg.parts.beam_depth) > 1e-9 * max(span, 1.0):
            raise ConfigError(
                f"{_at(source, lines, ('parts', 'beam_depth'))}: parts.beam_depth: {cfg.parts.beam_depth} disagrees "
                f"with offset.distances {cfg.offset.distances} (first to last layer = {span:g} mm); give one of "
                "them, or make them agree")


def _safe_name(stem: str) -> str:
    out = "".join(c if c.isalnum() or c in "_.=+-" else "_" for c in stem).lstrip("._-=+")
    return out or "run"


def _copy(data: Any, source: Path | str, depth: int = 0) -> Any:
    """A deep copy of nested dicts and lists (YAML aliases become separate copies), at most
    :data:`~fabricate.app.config_yaml.MAX_DEPTH` deep."""
    if depth > MAX_DEPTH:
        raise ConfigError(f"{source}: nested deeper than {MAX_DEPTH} levels; expected a config of sections and keys")
    if isinstance(data, dict):
        return {k: _copy(v, source, depth + 1) for k, v in data.items()}
    if isinstance(data, (list, tuple)):
        return [_copy(v, source, depth + 1) for v in data]
    return data
