"""The stages hand frozen, typed records to each other, and the report is built from the run record."""
from __future__ import annotations

import dataclasses
import inspect
import json
import types
import typing
from collections.abc import Mapping

import pytest

import fabricate.app.stages as stages
from _pipeline_fixtures import tiny_config
from fabricate.app import records
from fabricate.app.pipeline import run_pipeline


def _names() -> dict:
    """The names the records' annotations use (imported only for annotations there)."""
    from fabricate.cad.parts import Parts
    from fabricate.cad.spec import PartSpec
    from fabricate.app.config import RunConfig
    from fabricate.offset.structure import OffsetStructure
    from fabricate.structure.check import StructureCheck
    from optimize.mesh import Mesh
    from optimize.result import OptimizeResult

    return dict(vars(records), Mesh=Mesh, OptimizeResult=OptimizeResult, Parts=Parts, PartSpec=PartSpec,
                RunConfig=RunConfig, OffsetStructure=OffsetStructure, StructureCheck=StructureCheck)


def _conforms(value, hint, top: bool = True) -> bool:
    """Whether ``value`` is of the annotation ``hint`` (unions, tuple[X, ...], Mapping[K, V], classes);
    a record's own mapping (``top``) must be a read-only view."""
    if hint is typing.Any:
        return True
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        return any(_conforms(value, a, top) for a in args)
    if hint is type(None):
        return value is None
    if origin is tuple:
        return isinstance(value, tuple) and all(_conforms(v, args[0], top) for v in value)
    if origin is Mapping or hint is Mapping:
        # a record's mapping is a read-only view, never a dict a later stage could change
        kind = types.MappingProxyType if top else Mapping
        return isinstance(value, kind) and all(_conforms(k, args[0], False) and _conforms(v, args[1], False)
                                               for k, v in value.items())
    return isinstance(value, origin or hint)


@pytest.fixture(scope="module")
def captured(tmp_path_factory):
    """A tiny run whose report stage also hands its RunRecord to the test: (run record, run folder)."""
    tmp = tmp_path_factory.mktemp("records")
    seen = []
    original = stages.stage_report

    def keep(run):
        seen.append(run)
        return original(run)

    stages.stage_report = keep
    try:
        cfg = tiny_config(tmp, outputs={"bom": True, "step": False, "stl": False, "3mf": False, "dxf": False,
                                        "svg": False, "ifc": False, "3dm": False, "nc1": False, "gltf": False,
                                        "pictures": False, "html": False},
                          structure={"check": "report", "supports": "boundary"})
        summary = run_pipeline(cfg, tmp / "out")
    finally:
        stages.stage_report = original
    assert len(seen) == 1
    return seen[0], tmp / "out" / "tiny", summary


def test_every_record_of_a_run_is_frozen_and_of_its_declared_types(captured):
    run, _, _ = captured
    names = _names()
    checked = []
    todo = [run]
    while todo:
        rec = todo.pop()
        hints = typing.get_type_hints(type(rec), globalns=names)
        for f in dataclasses.fields(rec):
            value = getattr(rec, f.name)
            assert _conforms(value, hints[f.name]), (type(rec).__name__, f.name, type(value), hints[f.name])
            if dataclasses.is_dataclass(value) and type(value).__module__ == records.__name__:
                todo.append(value)
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(rec, dataclasses.fields(rec)[0].name, None)
        checked.append(type(rec).__name__)
    assert sorted(checked) == sorted(["RunRecord", "InputRecord", "OptimizeRecord", "OffsetRecord", "PartsRecord",
                                      "StructureRecord", "ExportsRecord", "Outcome"])
    assert run.structure.check is not None and run.parts.parts is not None  # the records were filled
    with pytest.raises(TypeError):
        run.measures["planarity"] = {}  # the mappings are read-only views


def test_the_report_is_built_from_the_run_record_alone(captured):
    """The report stage takes one argument, the run record; built again from that record (pointed at
    the published folder) it is report.json, apart from the clock and the files the report wrote."""
    from fabricate.report.document import build_report
    from fabricate.report.writer import write_report

    assert list(inspect.signature(write_report).parameters) == ["run"]
    assert list(inspect.signature(stages.stage_report).parameters) == ["run"]
    run, folder, summary = captured
    written = json.loads((folder / "report.json").read_text())
    again = build_report(dataclasses.replace(run, workdir=folder), written["pictures"])
    for key in set(written) | set(again):
        if key in ("created_utc", "files"):
            continue
        assert again[key] == written[key], key
    def results(files):  # not the run folder's own markers (the work folder's, then the published one's)
        return {f for f in files if not f.startswith(".conical-fab-")}

    assert results(again["files"]) == results(written["files"]) and "mesh.obj" in again["files"]
    assert written["status"] == run.outcome.status == summary.status
    assert written["notes"] == list(run.notes)


def test_the_built_in_design_is_built_once_per_run(tmp_path, monkeypatch):
    """Validating the config builds the design; the input stage uses that one, not a second."""
    import functools

    from optimize.modelling.designs import DESIGNS

    calls = []
    original = DESIGNS["dome"]

    @functools.wraps(original)
    def counted(*args, **kwargs):
        calls.append(kwargs)
        return original(*args, **kwargs)

    monkeypatch.setitem(DESIGNS, "dome", counted)
    cfg = tiny_config(tmp_path)
    inp = stages.stage_input(cfg)
    assert len(calls) == 1 and inp.mesh.n_faces == cfg.input.shape.design.mesh.n_faces > 0


def test_one_place_decides_the_method_of_a_strip_run(tmp_path):
    from optimize.modelling.hierarchy import STRIP_METHOD

    strip = tiny_config(tmp_path, optimize={"target": "strip"})
    method, kwargs = stages.optimizer_call(strip, "strip")
    assert method == kwargs["method"] == STRIP_METHOD != "default"
    method, kwargs = stages.optimizer_call(tiny_config(tmp_path, optimize={"target": "pq"}), "pq")
    assert method == "default" and kwargs["formulation"] == "auto"
    sqp = tiny_config(tmp_path, optimize={"target": "strip", "method": "sqp"})
    assert stages.optimizer_call(sqp, "strip")[0] == "sqp" and "formulation" not in stages.optimizer_call(sqp, "strip")[1]


def test_the_readme_layout_shows_every_package_and_the_stages_in_run_order():
    import re
    from pathlib import Path

    from fabricate.app.pipeline import STAGES

    repo = Path(__file__).resolve().parents[1]
    layout = (repo / "docs" / "layout.md").read_text()  # the README's layout moved there
    packages = sorted(p.parent.name for p in (repo / "fabricate").glob("*/__init__.py"))
    assert packages and all(re.search(rf"^  {name}/ ", layout, re.M) for name in packages), packages
    shown = re.findall(r"stage_(\w+)", layout)
    assert shown == list(STAGES), shown  # the picture's stages are the pipeline's, in its order
    for name in ("InputRecord", "OptimizeRecord", "OffsetRecord", "PartsRecord", "StructureRecord",
                 "ExportsRecord", "RunRecord"):
        assert name in layout and hasattr(records, name), name


def test_fabricate_optimize_runs_a_strip_with_the_method_a_run_would_use(tmp_path, capsys):
    """``fabricate optimize --target strip`` (method default) runs what a config with target strip runs,
    instead of refusing the default method."""
    from fabricate.app.cli import main
    from optimize.modelling import shapes
    from optimize.modelling.hierarchy import STRIP_METHOD
    from optimize.mesh.io import write_mesh

    strip = shapes.perturbed(shapes.grid(6, 2, size=(5, 1), height=lambda x, y: 0.1 * x * y), 0.1, seed=3)
    write_mesh(tmp_path / "strip.obj", strip)
    code = main(["optimize", str(tmp_path / "strip.obj"), "-o", str(tmp_path / "out.obj"), "--target", "strip",
                 "--max-iter", "30", "--progress", "off"])
    out = capsys.readouterr().out
    assert code in (0, 3) and f", {STRIP_METHOD}/strip)" in out, out
