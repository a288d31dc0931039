"""Issue 30 item 6: a .3dm file's model unit (Rhino's ModelUnitSystem) is used when the config or
``--units`` gives none, said in the notes; when both are given and differ, the config's wins and a
warning says so."""
from __future__ import annotations

import json
import logging

import numpy as np
import pytest

rhino3dm = pytest.importorskip("rhino3dm")

from fabricate.app.cli import main  # noqa: E402
from fabricate.app.config import load_config, mesh_file_units  # noqa: E402
from optimize.errors import ConfigError  # noqa: E402
from optimize.mesh.io import read_mesh  # noqa: E402
from optimize.mesh.io.api import mesh_units  # noqa: E402
from optimize.modelling import shapes  # noqa: E402


def _dome_m():
    """A conical dome, 8 m radius, coordinates in metres."""
    return shapes.revolution(shapes.dome_profile(radius=8.0, rise=3.0, k=4), 8, name="dome")


def write_3dm(path, mesh, unit: str = "Meters") -> None:
    """``mesh`` as the one Mesh object of a .3dm file whose model unit is ``unit``."""
    model = rhino3dm.File3dm()
    model.Settings.ModelUnitSystem = getattr(rhino3dm.UnitSystem, unit)
    m = rhino3dm.Mesh()
    m.Vertices.UseDoublePrecisionVertices = True
    for p in mesh.V.tolist():
        m.Vertices.Add(*p)
    for f in mesh.F.tolist():
        m.Faces.AddFace(*[i for i in f if i >= 0])
    model.Objects.AddMesh(m)
    assert model.Write(str(path), 7)


@pytest.fixture
def roof_m(tmp_path):
    path = tmp_path / "roof.3dm"
    write_3dm(path, _dome_m())
    return path


def test_the_reader_names_the_files_unit(roof_m):
    assert mesh_units(roof_m) == ("Meters", 1000.0)
    mesh = read_mesh(roof_m)
    assert np.allclose(mesh.V, _dome_m().V)  # coordinates as in the file
    assert any("the file's model unit: Meters (1000 mm)" in n for n in mesh.notes), mesh.notes
    assert mesh_units(roof_m.with_suffix(".obj")) is None  # OBJ states no unit


def test_without_units_the_config_reads_the_files_unit(roof_m, caplog):
    cfg_path = roof_m.parent / "job.yaml"
    cfg_path.write_text("input: {mesh: roof.3dm}\n")
    with caplog.at_level(logging.INFO, logger="fabricate.app.config"):
        cfg = load_config(cfg_path)
    assert cfg.units == "m" and cfg.mm_per_unit == 1000.0
    assert "read in m, the file's model unit (Meters); units not given" in cfg.units_note
    assert cfg.as_dict()["units"] == "m"  # the config as run says it
    assert any("the file's model unit (Meters)" in r.getMessage() for r in caplog.records)


def test_the_input_stage_scales_by_the_files_unit(roof_m):
    from fabricate.app.stages import stage_input

    cfg_path = roof_m.parent / "job.yaml"
    cfg_path.write_text("input: {mesh: roof.3dm}\nsubdivision: {levels: 0}\n")
    record = stage_input(load_config(cfg_path))
    assert record.facts["units"] == "m" and record.facts["mm_per_unit"] == 1000.0
    assert np.allclose(record.mesh.V, 1000.0 * _dome_m().V)
    assert any("Meters" in n for n in record.notes)


def test_the_configs_units_win_with_a_warning(roof_m, caplog):
    cfg_path = roof_m.parent / "job.yaml"
    cfg_path.write_text("input: {mesh: roof.3dm}\nunits: mm\n")
    with caplog.at_level(logging.WARNING, logger="fabricate.app.config"):
        cfg = load_config(cfg_path)
    assert cfg.units == "mm"
    warned = [r for r in caplog.records if r.levelno == logging.WARNING]
    assert warned and "units mm overrides the file's model unit Meters (1000 mm)" in warned[0].getMessage()
    cfg_path.write_text("input: {mesh: roof.3dm}\nunits: m\n")  # the same: no warning, a note
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="fabricate.app.config"):
        assert load_config(cfg_path).units == "m"
    assert not caplog.records


def test_a_unit_the_config_cannot_name_is_refused_unless_given(tmp_path):
    path = tmp_path / "site.3dm"
    write_3dm(path, _dome_m(), unit="Kilometers")
    (tmp_path / "job.yaml").write_text("input: {mesh: site.3dm}\n")
    with pytest.raises(ConfigError) as info:
        load_config(tmp_path / "job.yaml")
    message = str(info.value)
    assert info.value.exit_code == 2 and "job.yaml:1: input.mesh:" in message
    assert "Kilometers (1e+06 mm)" in message and "scale: 1000" in message, message
    (tmp_path / "job.yaml").write_text("input: {mesh: site.3dm}\nunits: m\nscale: 1000\n")
    assert load_config(tmp_path / "job.yaml").mm_per_unit == 1e6


def test_a_file_without_a_unit_keeps_mm(tmp_path):
    path = tmp_path / "none.3dm"
    write_3dm(path, _dome_m(), unit="None")
    unit, note, overridden = mesh_file_units(path, None)
    assert unit == "mm" and "states no model unit" in note and not overridden


def test_measure_reads_the_files_unit_and_says_so(roof_m, capsys):
    assert main(["measure", str(roof_m)]) == 0
    captured = capsys.readouterr()
    s = json.loads(captured.out)  # the note goes to stderr: stdout stays JSON
    assert s["units"]["file"] == "m" and s["units"]["mm_per_unit"] == 1000.0
    assert "note:" in captured.err and "read in m, the file's model unit (Meters)" in captured.err
    assert main(["measure", str(roof_m), "--units", "mm"]) == 0
    captured = capsys.readouterr()
    t = json.loads(captured.out)
    assert t["units"]["file"] == "mm" and "warning:" in captured.err and "--units mm overrides" in captured.err
    assert s["edge_length"]["mean"] == pytest.approx(1000.0 * t["edge_length"]["mean"])


def test_remesh_reads_the_files_unit_and_writes_in_it(tmp_path, capsys):
    from optimize.remesh import surfaces

    roof = surfaces.height_field(size=(4.0, 3.0), n=(13, 10))  # metres
    src, out = tmp_path / "roof.3dm", tmp_path / "quads.obj"
    write_3dm(src, roof.mesh)
    assert main(["remesh", str(src), "--edge-length", "0.5", "--side=0,0,-1", "-o", str(out), "--optimize",
                 "none"]) == 0
    captured = capsys.readouterr()
    assert "read in m" in captured.err and "(written in m)" in captured.out and "target 500 mm" in captured.out
    assert read_mesh(out).n_faces < 100  # 0.5 m, not 0.5 mm


def test_fabricate_optimize_reads_a_3dm_in_its_own_unit_and_writes_it_back_in_it(roof_m, tmp_path, capsys):
    """#30 item 6: ``fabricate optimize`` took a .3dm in metres as millimetres (a 16 mm dome)."""
    report = tmp_path / "rep.json"
    code = main(["optimize", str(roof_m), "-o", str(tmp_path / "out.obj"), "--target", "pq", "--report", str(report)])
    err = capsys.readouterr().err
    assert code == 0, err
    assert "note:" in err and "Meters" in err
    rep = json.loads(report.read_text())
    assert rep["units"] == "m"
    written = read_mesh(tmp_path / "out.obj")
    assert np.abs(written.V - _dome_m().V).max() < 0.05 * _dome_m().bbox_diagonal()  # metres in, metres out
