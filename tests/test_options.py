"""One source of defaults: the config sections are derived from the frozen option objects."""
import dataclasses
import typing

import pytest
from pydantic import ValidationError

from fabricate.app import options
from fabricate.app.config import OffsetSection, OutputsSection, RunConfig, TolerancesSection
from fabricate.app.config_section import OPTIONS, Section
from fabricate.app.config_structure import LoadsOption, StructureSection
from fabricate.structure.options import LoadsOptions, StructureOptions
from optimize.tolerances import Tolerances


def _frozen(value):
    if isinstance(value, Section):  # a nested section: its frozen object
        return value.to_options()
    return tuple(value) if isinstance(value, list) else value


@pytest.mark.parametrize("section,cls", [(OffsetSection, options.OffsetOptions),
                                         (OutputsSection, options.OutputsOptions),
                                         (TolerancesSection, Tolerances), (RunConfig, options.RunOptions),
                                         (StructureSection, StructureOptions), (LoadsOption, LoadsOptions)])
def test_every_config_default_is_the_option_objects(section, cls):
    assert OPTIONS[section.__mro__[1]] is cls  # derived, not written again
    defaults = cls()
    for f in dataclasses.fields(cls):
        key = section.model_fields[f.name]
        assert _frozen(key.get_default(call_default_factory=True)) == getattr(defaults, f.name), f.name
        for bound in ("ge", "gt", "le", "lt"):
            value = f.metadata.get(bound, (options.TOLERANCE_KEYS.get(f.name, {}) if cls is Tolerances else {})
                                   .get(bound))
            if value is not None:  # the bound of the option is the key's
                assert any(getattr(m, bound, None) == value for m in key.metadata), (f.name, bound)
    if section is not RunConfig:
        assert section().to_options() == defaults  # and back


def test_a_derived_key_keeps_its_bounds_alias_and_strictness():
    with pytest.raises(ValidationError):
        TolerancesSection(planarity=2.0)  # le=1 from TOLERANCE_KEYS
    with pytest.raises(ValidationError):
        OffsetSection(distances=[0.0, 2 * options.MAX_MM])  # the items' bound
    with pytest.raises(ValidationError):
        OutputsSection.model_validate({"mesh": "yes please"})  # strict booleans
    assert OutputsSection.model_validate({"3mf": False}).three_mf is False  # the alias
    assert OutputsSection.model_validate({"check": False}).check == "off"  # YAML's off as the word
    assert OffsetSection(distances=[0, -200]).to_options() == options.OffsetOptions(distances=(0.0, -200.0))


def test_the_structure_section_is_on_the_strict_base():
    assert issubclass(StructureSection, Section) and issubclass(LoadsOption, Section)
    data = {"section": {"shape": "rhs", "depth": 200, "width": 60, "web": 4}, "supports": [0, 3],
            "combinations": [{"name": "ULS", "kind": "uls", "factors": {"snow": 1.5}}],
            "sizing": {"sections": [{"depth": 200, "width": 8}]}}
    frozen = StructureSection.model_validate(data).to_options()  # what the structure stage takes
    assert frozen.section.properties().name == StructureOptions(section=frozen.section).section.properties().name
    assert frozen.supports == (0, 3) and frozen.combination_list() == [("ULS", "uls", {"snow": 1.5})]
    assert frozen.sizing.sections[0].shape == "plate" and frozen.sizing.sections[0].width == 8
    for bad in ({"loads": {"snow": float("inf")}}, {"loads": {"snow": "0.8"}}, {"gamma_m0": True}):
        with pytest.raises(ValidationError):
            StructureSection.model_validate(bad)
    assert StructureSection.model_validate({"up": [0, 0, 1], "check": False}).up == (0.0, 0.0, 1.0)


def test_the_command_line_reads_its_defaults_from_the_option_objects(monkeypatch):
    from fabricate.app.cli import build_parser

    parser = build_parser()
    run = parser.parse_args(["run", "x.yaml"])
    batch = parser.parse_args(["batch", "x.yaml"])
    assert run.out == batch.out == options.COMMAND.out_root and batch.workers == options.COMMAND.workers
    monkeypatch.setattr(options, "COMMAND", options.CommandOptions(out_root="elsewhere"))
    assert build_parser().parse_args(["run", "x.yaml"]).out == "elsewhere"  # read, not written again


def test_the_optimize_section_and_command_take_the_optimizers_defaults():
    """fabricate's optimize section and ``fabricate optimize`` read optimize.options (one place)."""
    import optimize.options as opt
    from fabricate.app.cli import build_parser
    from fabricate.app.config import OptimizeSection

    section = OptimizeSection()
    for key in ("method", "formulation", "linear_solver", "torsion_free_beams", "fairness", "closeness",
                "max_iter", "glide_boundary", "convex"):
        assert getattr(section, key) == getattr(opt.DEFAULTS, key), key
    for key in ("method", "formulation", "linear_solver"):
        assert set(typing.get_args(OptimizeSection.model_fields[key].annotation)) == set(opt.CHOICES[key])
    args = build_parser().parse_args(["optimize", "in.obj", "-o", "out.obj"])
    assert (args.fairness, args.closeness, args.max_iter) == (opt.DEFAULTS.fairness, opt.DEFAULTS.closeness,
                                                               opt.DEFAULTS.max_iter)


@pytest.mark.parametrize("name", ["PartSpec", "Limits", "BeamSpec", "NodeSpec"])
def test_the_parts_sections_are_derived_from_the_part_spec(name):
    """Defaults and bounds of ``parts`` are the frozen part dimensions' (fabricate.cad.spec), written once."""
    from fabricate.app import config_parts
    from fabricate.cad import spec

    cls = getattr(spec, name)
    section = {"PartSpec": config_parts.PartsSection, "Limits": config_parts.LimitsSection,
               "BeamSpec": config_parts.BeamSection, "NodeSpec": config_parts.NodeSection}[name]
    assert OPTIONS[section.__mro__[1]] is cls
    assert section().to_options() == cls()  # the nested sections back as their frozen objects too
    if name == "Limits":  # a YAML list for a fixed-length tuple key, taken by every derived section
        assert section.model_validate({"sheet_mm": [3000, 2000]}).to_options().sheet_mm == (3000.0, 2000.0)
    for f in dataclasses.fields(cls):
        key = section.model_fields[f.name]
        if not dataclasses.is_dataclass(f.default) and f.name != "glass":
            assert _frozen(key.get_default(call_default_factory=True)) == f.default, f.name
        for bound in ("ge", "gt", "le", "lt"):
            if bound in f.metadata:
                assert any(getattr(m, bound, None) == f.metadata[bound] for m in key.metadata), (f.name, bound)


def test_the_joint_gap_rule_is_the_part_specs_with_the_line_of_a_key_it_names(tmp_path):
    from fabricate.app.config import load_config
    from fabricate.cad.spec import PartSpec
    from optimize.errors import ConfigError

    with pytest.raises(ConfigError, match="parts.joint_gap = 10 mm is not below parts.beam_width = 8 mm"):
        PartSpec(beam_width=8.0)
    path = tmp_path / "job.yaml"
    path.write_text("name: job\ninput: {shape: {name: dome}}\nparts:\n  edge: axis\n  beam_width: 8\n")
    with pytest.raises(ConfigError) as err:  # joint_gap is not in the file: the line of beam_width
        load_config(path)
    assert str(err.value).startswith(f"{path}:5: parts.joint_gap = 10 mm is not below parts.beam_width"), err.value
    path.write_text("name: job\ninput: {shape: {name: dome}}\nparts:\n  beam_width: 8\n  joint_gap: 9\n")
    with pytest.raises(ConfigError, match=r"job.yaml:5: parts.joint_gap = 9 mm"):
        load_config(path)


def test_the_shared_command_line_arguments_parse_alike(tmp_path, capsys):
    """--set / --out / --force / -o of several subcommands come from fabricate.app.cli.args."""
    from fabricate.app.cli import build_parser, main

    parser = build_parser()
    for argv in (["run", "c.yaml"], ["size", "c.yaml"], ["batch", "c.yaml"]):
        args = parser.parse_args(argv + ["--set", "a.b=1", "--set", "c=2"])
        assert args.sets == ["a.b=1", "c=2"], argv
    run = parser.parse_args(["run", "c.yaml", "--force", "-q"])
    assert (run.force, run.quiet, run.out) == (True, True, options.COMMAND.out_root)
    for argv in (["optimize", "m.obj", "-o", "x.obj"], ["remesh", "s.obj", "--edge-length", "1", "--output", "x.obj"],
                 ["shapes", "dome", "-o", "x.obj"]):
        assert parser.parse_args(argv).output == "x.obj", argv
    path = tmp_path / "c.yaml"
    path.write_text("name: c\ninput: {shape: {name: dome}}\n")
    assert main(["size", str(path), "--set", "parts.joint_gap=8,9"]) == 2
    assert "--set parts.joint_gap: fabricate size takes one value per key" in capsys.readouterr().err


def test_the_optimize_section_is_derived_from_the_optimizers_options():
    """Defaults, choices, bounds and help of ``optimize`` are the fields of optimize.options.OptimizeOptions,
    written once; only ``target`` (null: the input's own, ``none``) and ``fixed`` are the section's own."""
    import optimize.options as opt
    from fabricate.app.config import OptimizeSection

    assert OPTIONS[OptimizeSection.__mro__[1]] is opt.OptimizeOptions
    app_only = {"target", "fixed"}
    hints = typing.get_type_hints(opt.OptimizeOptions)
    derived = [f for f in dataclasses.fields(opt.OptimizeOptions) if f.name not in app_only | {"tol", "paper"}]
    assert set(OptimizeSection.model_fields) == app_only | {f.name for f in derived}
    bounds = ("ge", "gt", "le", "lt")
    for f in derived:
        key = OptimizeSection.model_fields[f.name]
        assert key.get_default() == f.default == getattr(opt.DEFAULTS, f.name), f.name
        assert key.annotation == hints[f.name], f.name  # the choices are the option's Literal
        assert key.description == f.metadata["help"], f.name
        given = {b: getattr(m, b) for m in key.metadata for b in bounds if getattr(m, b, None) is not None}
        assert given == {b: f.metadata[b] for b in bounds if b in f.metadata}, f.name  # no bound of the app's own
    assert (opt.OptimizeOptions.__dataclass_fields__["max_iter"].metadata["le"] == opt.MAX_ITER
            and opt.OptimizeOptions.__dataclass_fields__["fairness"].metadata["le"] == opt.MAX_WEIGHT)
    for bad in ({"max_iter": 0}, {"max_iter": opt.MAX_ITER + 1}, {"fairness": -1e-9}, {"closeness": 2 * opt.MAX_WEIGHT},
                {"method": "newton"}, {"torsion_free_beams": "yes please"}):
        with pytest.raises(ValidationError):
            OptimizeSection.model_validate(bad)
    assert OptimizeSection.model_validate({"max_iter": opt.MAX_ITER, "closeness": opt.MAX_WEIGHT}).max_iter == opt.MAX_ITER
    with pytest.raises(opt.ConfigError, match=r"fairness: weight -1.0, expected a finite number >= 0"):
        opt.OptimizeOptions(fairness=-1.0)  # the object holds the same lower bound
