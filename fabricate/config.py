"""Run configurations: YAML files validated by a pydantic schema.

A config names the input (a built-in design, a mesh file, a control mesh or a
triangle surface), the subdivision and optimization settings, the tolerances,
the offset layers and part dimensions (mm), the files to write and the units
of the input.  ``configs/reference.yaml`` lists every key with its default.

Every mistake is a :class:`optimize.errors.ConfigError` whose message names the
file and line, the key path, the value and what is allowed, with a
did-you-mean for misspelt keys::

    configs/dome.yaml:7: optimize.targte: unknown key (did you mean 'target'?); allowed: ...

Files are read with ``yaml.safe_load`` only; paths in a config are resolved
relative to the config file's folder.
"""
from __future__ import annotations

import inspect
import math
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import (BaseModel, ConfigDict, Field, PrivateAttr, ValidationError, ValidationInfo,
                      field_validator, model_validator)
from pydantic_core import PydanticCustomError

from optimize.errors import ConfigError
from optimize.tolerances import Tolerances

from .config_errors import did_you_mean, format_errors, key_lines

UNIT_TO_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4, "ft": 304.8}
INPUT_KINDS = ("shape", "mesh", "control", "surface")


class Section(BaseModel):
    """A config section: unknown keys are errors (named with a did-you-mean by :func:`format_errors`)."""

    model_config = ConfigDict(extra="forbid", validate_default=True, populate_by_name=True)

    @classmethod
    def allowed_keys(cls) -> list[str]:
        return [f.alias or name for name, f in cls.model_fields.items()]


def _resolve_path(value: Any, info: ValidationInfo) -> Path | None:
    """A path relative to the config file's folder; the file must exist."""
    if value is None:
        return None
    if not isinstance(value, (str, Path)) or not str(value).strip():
        raise PydanticCustomError("path", "expected a file path (a string)")
    base = Path((info.context or {}).get("base_dir", "."))
    path = Path(value).expanduser()
    full = (path if path.is_absolute() else base / path).resolve()
    if not full.is_file():
        raise PydanticCustomError("path_missing", "file not found: {full} (resolved relative to {base})",
                                  {"full": str(full), "base": str(base.resolve())})
    return full


class ShapeInput(Section):
    """A built-in design of :mod:`optimize.designs` with its parameters."""

    name: str
    params: dict[str, Any] = Field(default_factory=dict)

    @model_validator(mode="after")
    def _known_design(self) -> "ShapeInput":
        try:
            from optimize.designs import DESIGNS
        except ImportError as exc:  # the modelling package is not installed
            raise PydanticCustomError("designs", "built-in designs are not available ({err})",
                                      {"err": str(exc)}) from None
        if self.name not in DESIGNS:
            raise PydanticCustomError(
                "design", "unknown design '{name}'{hint} (allowed: {allowed})",
                {"name": self.name, "hint": did_you_mean(self.name, DESIGNS),
                 "allowed": ", ".join(sorted(DESIGNS))})
        _check_params(DESIGNS[self.name], self.params)
        try:  # the design checks its own parameter values; building a control mesh is cheap
            DESIGNS[self.name](**self.params)
        except ConfigError as exc:
            raise PydanticCustomError("design_value", "{err}", {"err": str(exc)}) from None
        return self


def _check_params(fn, params: dict[str, Any]) -> None:
    """Raise for a parameter the design function does not take."""
    sig = inspect.signature(fn)
    if any(p.kind is p.VAR_KEYWORD for p in sig.parameters.values()):
        return
    allowed = [n for n, p in sig.parameters.items() if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
    for key in params:
        if key not in allowed:
            raise PydanticCustomError(
                "design_param", "unknown parameter '{key}'{hint} (allowed: {allowed})",
                {"key": key, "hint": did_you_mean(key, allowed), "allowed": ", ".join(allowed) or "none"})


class InputSection(Section):
    """Exactly one of ``shape``, ``mesh``, ``control`` or ``surface``."""

    shape: ShapeInput | None = None
    mesh: Path | None = None
    control: Path | None = None
    surface: Path | None = None
    edge_length: float | None = Field(default=None, gt=0)
    irregular: Literal["faces", "vertices", "nearest"] | None = None
    side: Literal["keep"] | tuple[float, float, float] | None = None
    radius: float | None = Field(default=None, gt=0)
    layer: str | None = Field(default=None, min_length=1, max_length=500)
    object: str | None = Field(default=None, min_length=1, max_length=500)

    _paths = field_validator("mesh", "control", "surface", mode="before")(_resolve_path)

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
        rhino = self.mesh is not None and self.mesh.suffix.lower() == ".3dm"
        for key in ("layer", "object"):
            if getattr(self, key) is not None and not rhino:
                raise PydanticCustomError(key, "{key} picks a mesh in a .3dm file given as input.mesh",
                                          {"key": key})
        if self.surface is None and self.radius is not None:
            raise PydanticCustomError("radius", "radius applies only to a surface input")
        if isinstance(self.side, tuple) and not (all(math.isfinite(c) for c in self.side) and any(self.side)):
            raise PydanticCustomError("side", "side {side} is not a nonzero finite vector, expected "
                                      "[x, y, z] toward the inside or 'keep'", {"side": list(self.side)})
        return self

    @property
    def kind(self) -> str:
        return next(k for k in INPUT_KINDS if getattr(self, k) is not None)


class SubdivisionSection(Section):
    """``null`` means: the built-in design's own (else catmull_clark, 2 levels for a control mesh,
    0 otherwise); chaikin and lane_riesenfeld refine developable strips."""

    scheme: Literal["catmull_clark", "doo_sabin", "chaikin", "lane_riesenfeld"] | None = None
    levels: int | None = Field(default=None, ge=0, le=6)


class OptimizeSection(Section):
    target: Literal["pq", "conical", "circular", "strip", "none"] | None = None
    method: Literal["default", "penalty", "sqp", "hybrid"] = "default"
    formulation: Literal["auto", "auxiliary", "vertices"] = "auto"
    linear_solver: Literal["auto", "pardiso", "superlu", "cholespy", "eliminate"] = "auto"
    torsion_free_beams: Literal["auto"] | bool = "auto"
    fairness: float = Field(default=1e-3, ge=0)
    closeness: float = Field(default=1e-2, ge=0)
    max_iter: int = Field(default=200, ge=1, le=100000)
    fixed: Literal["boundary", "corners"] | list[int] | None = None
    glide_boundary: bool = False

    @field_validator("fixed")
    @classmethod
    def _indices(cls, v):
        if isinstance(v, list) and any(i < 0 for i in v):
            raise PydanticCustomError("fixed", "vertex indices must be >= 0")
        return v


_TOL = Tolerances()


class TolerancesSection(Section):
    """Thresholds (see :class:`optimize.tolerances.Tolerances`): relative, radians, or mm."""

    planarity: float = Field(default=_TOL.planarity, gt=0)
    conical: float = Field(default=_TOL.conical, gt=0)
    circular: float = Field(default=_TOL.circular, gt=0)
    offset: float = Field(default=_TOL.offset, gt=0)
    beam_planarity: float = Field(default=_TOL.beam_planarity, gt=0)
    cad_linear_mm: float = Field(default=_TOL.cad_linear_mm, gt=0)
    closeness: float = Field(default=_TOL.closeness, gt=0)

    def to_tolerances(self) -> Tolerances:
        return Tolerances(**self.model_dump())


class OffsetSection(Section):
    """Layer distances in mm (signed, along the face normals); ``null``: ``[0, -beam_depth]``."""

    distances: list[float] | None = Field(default=None, min_length=2)
    flip: bool = False

    @field_validator("distances")
    @classmethod
    def _distinct(cls, v):
        if v is not None and len(set(v)) != len(v):
            raise PydanticCustomError("distances", "layer distances must be distinct")
        return v


class PartsSection(Section):
    """Part dimensions in mm and densities in kg/m3 (see ``fabricate.cad.PartSpec``)."""

    glass_thickness: float = Field(default=10.0, gt=0)
    joint_gap: float = Field(default=10.0, ge=0)
    edge: Literal["auto", "axis", "perpendicular"] = "auto"
    beam_width: float = Field(default=60.0, gt=0)
    beam_depth: float = Field(default=200.0, gt=0)
    node_radius: float = Field(default=0.0, ge=0)
    density_glass: float = Field(default=2500.0, gt=0)
    density_steel: float = Field(default=7850.0, gt=0)
    node_sides: int = Field(default=24, ge=6)


CHECK_AUTO_MAX_PARTS = 3000
"""``outputs.check: auto`` runs the full check up to this many parts, the fast one above."""


class OutputsSection(Section):
    """Which files to write (``true``/``false``); report.json is always written.

    ``check``: how the written files are re-validated (``fabricate.check``):
    ``full`` (every check, with OpenCASCADE reading model.step back: about 10 ms
    per part), ``fast`` (the same without the STEP read-back), ``off``, or
    ``auto`` (full up to :data:`CHECK_AUTO_MAX_PARTS` parts, fast above).
    """

    mesh: bool = True
    layers: bool = True
    step: bool = True
    stl: bool = True
    three_mf: bool = Field(default=True, alias="3mf")
    dxf: bool = True
    svg: bool = True
    bom: bool = True
    ifc: bool = True
    rhino: bool = Field(default=True, alias="3dm")
    nc1: bool = True
    gltf: bool = True
    step_schema: Literal["AP214", "AP242"] = "AP214"
    pictures: bool = True
    html: bool = True
    check: Literal["auto", "full", "fast", "off"] = "auto"
    overwrite: bool = False  # replace an earlier finished run (as ``fabricate run --force``)

    def check_mode(self, parts: int) -> str:
        """``full`` | ``fast`` | ``off`` for a model of ``parts`` parts (``auto`` resolved)."""
        if self.check != "auto":
            return self.check
        return "full" if parts <= CHECK_AUTO_MAX_PARTS else "fast"


class RunConfig(Section):
    """A whole run configuration (one YAML file)."""

    name: str | None = Field(default=None, pattern=r"^[A-Za-z0-9][A-Za-z0-9_.=+-]*$", max_length=120)
    input: InputSection
    subdivision: SubdivisionSection = Field(default_factory=SubdivisionSection)
    optimize: OptimizeSection = Field(default_factory=OptimizeSection)
    tolerances: TolerancesSection = Field(default_factory=TolerancesSection)
    offset: OffsetSection = Field(default_factory=OffsetSection)
    parts: PartsSection = Field(default_factory=PartsSection)
    outputs: OutputsSection = Field(default_factory=OutputsSection)
    units: Literal["mm", "cm", "m", "in", "ft"] = "mm"
    scale: float = Field(default=1.0, gt=0)

    _source: Path | None = PrivateAttr(default=None)

    @property
    def source(self) -> Path | None:
        """The config file this came from (None for a dict)."""
        return self._source

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


# -- loading ---------------------------------------------------------------
def load_config(path: str | Path, overrides: dict[str, Any] | None = None) -> RunConfig:
    """Read and validate a YAML config file.

    overrides : ``{"parts.glass_thickness": 8, ...}`` applied to the YAML data
        before validation (the ``--set`` of ``fabricate run`` / ``batch``).

    Raises ConfigError naming the file, line, key path, value and what is allowed.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read the config file ({exc.strerror or exc})") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"{path}:{mark.line + 1}" if mark else str(path)
        problem = getattr(exc, "problem", None) or str(exc)
        raise ConfigError(f"{where}: not valid YAML: {problem}") from None
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping of sections (name, input, ...), "
                          f"found {type(data).__name__}")
    cfg = parse_config(data, source=path, overrides=overrides, lines=key_lines(text))
    return cfg


def parse_config(data: dict[str, Any], *, source: str | Path = "<config>", base_dir: str | Path | None = None,
                 overrides: dict[str, Any] | None = None, lines: dict[tuple, int] | None = None) -> RunConfig:
    """Validate a config dict (``source`` names it in messages; paths relative to ``base_dir``,
    default the folder of ``source``)."""
    source = Path(source)
    base = Path(base_dir) if base_dir is not None else source.parent
    data = _copy(data)
    for key, value in (overrides or {}).items():
        set_key(data, key, value, source=source)
    try:
        cfg = RunConfig.model_validate(data, context={"base_dir": base})
    except ValidationError as exc:
        raise ConfigError(format_errors(exc, source, lines or {}, overrides or {}, RunConfig)) from None
    if cfg.name is None:
        cfg.name = _safe_name(source.stem)
    cfg._source = source
    _cross_checks(cfg, source, lines or {})
    return cfg


def _cross_checks(cfg: RunConfig, source: Path, lines: dict[tuple, int]) -> None:
    if cfg.input.shape is not None and "units" in cfg.model_fields_set and cfg.units != "mm":
        line = lines.get(("units",))
        raise ConfigError(f"{source}{f':{line}' if line else ''}: units: {cfg.units!r} applies to mesh files; "
                          "built-in designs are in mm (their sizes are parameters); expected mm or no units key "
                          "(scale still applies)")
    parts = cfg.parts
    if parts.joint_gap >= parts.beam_width:
        line = lines.get(("parts", "joint_gap")) or lines.get(("parts", "beam_width"))
        raise ConfigError(f"{source}{f':{line}' if line else ''}: parts.joint_gap: {parts.joint_gap:g} mm is not "
                          f"below parts.beam_width {parts.beam_width:g} mm; expected a smaller gap so that the "
                          "panels bear on the beams")
    if cfg.offset.distances is not None and "beam_depth" in cfg.parts.model_fields_set:
        span = abs(cfg.offset.distances[-1] - cfg.offset.distances[0])
        if abs(span - cfg.parts.beam_depth) > 1e-9 * max(span, 1.0):
            line = lines.get(("parts", "beam_depth"))
            raise ConfigError(
                f"{source}{f':{line}' if line else ''}: parts.beam_depth: {cfg.parts.beam_depth} disagrees with offset.distances "
                f"{cfg.offset.distances} (first to last layer = {span:g} mm); give one of them, or make them agree")


def _safe_name(stem: str) -> str:
    out = "".join(c if c.isalnum() or c in "_.=+-" else "_" for c in stem).lstrip("._-=+")
    return out or "run"


def _copy(data: Any) -> Any:
    if isinstance(data, dict):
        return {k: _copy(v) for k, v in data.items()}
    if isinstance(data, list):
        return [_copy(v) for v in data]
    return data


def set_key(data: dict[str, Any], dotted: str, value: Any, *, source: str | Path = "--set") -> None:
    """Set ``data["a"]["b"] = value`` for ``dotted = "a.b"``, creating sections as needed."""
    parts = [p for p in dotted.split(".")]
    if not dotted or any(not p for p in parts):
        raise ConfigError(f"{source}: --set {dotted}={value!r}: expected a key path like parts.glass_thickness")
    node = data
    for i, key in enumerate(parts[:-1]):
        child = node.get(key)
        if child is None:
            child = node[key] = {}
        if not isinstance(child, dict):
            raise ConfigError(f"{source}: --set {dotted}: {'.'.join(parts[:i + 1])} is {child!r}, "
                              "not a section with keys")
        node = child
    node[parts[-1]] = value


def parse_value(text: str) -> Any:
    """A ``--set`` value: YAML scalar or list (``8`` -> 8, ``true`` -> True, ``[0, -200]`` -> list)."""
    try:
        return yaml.safe_load(text) if text.strip() else ""
    except yaml.YAMLError:
        return text
