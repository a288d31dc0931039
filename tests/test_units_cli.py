"""Issue 30 item 6: a length given on the command line is in ``--units``, as ``input.edge_length`` is in
the config's ``units`` (``remesh --units m --edge-length 1.5`` is 1.5 m); part dimensions
(``offset --distances``) are mm, as ``offset.distances`` is; the --help text says which."""
from __future__ import annotations

import json

import numpy as np
import pytest

from fabricate.app.cli import main
from optimize.mesh import measures
from optimize.mesh.io import read_mesh, write_mesh
from optimize.remesh import surfaces


@pytest.fixture(scope="module")
def roof():
    """A 4 m x 3 m height field, coordinates in metres."""
    return surfaces.height_field(size=(4.0, 3.0), n=(13, 10))


@pytest.mark.parametrize("units, scale", [("m", 1.0), ("cm", 100.0), ("mm", 1000.0)])
def test_remesh_edge_length_and_radius_are_in_units(tmp_path, roof, capsys, units, scale):
    """The same roof written in m, cm and mm, remeshed at 0.5 m given in each file's unit: the same
    quads (in mm), the report's target 500 mm and the kernel radius 1,200 mm."""
    src, out, rep = tmp_path / f"roof_{units}.obj", tmp_path / f"quads_{units}.obj", tmp_path / "rep.json"
    write_mesh(src, roof.mesh.with_vertices(roof.mesh.V * scale))
    code = main(["remesh", str(src), "--units", units, "--edge-length", f"{0.5 * scale:g}", "--radius",
                 f"{1.2 * scale:g}", "-o", str(out), "--optimize", "none", "--report", str(rep)])
    assert code == 0, capsys.readouterr().err
    facts = json.loads(rep.read_text())
    assert facts["edge_length"] == {"given": 0.5 * scale, "units": units, "mm": pytest.approx(500.0)}
    assert facts["remesh"]["edge_length_target"] == pytest.approx(500.0)
    assert facts["remesh"]["radius"] == pytest.approx(1200.0)
    assert 400.0 < facts["remesh"]["edge_length"]["mean"] < 600.0
    quads = read_mesh(out)  # written in the input's unit
    assert 0.4 * scale < measures.edge_lengths(quads).mean() < 0.6 * scale
    assert "target 500 mm" in capsys.readouterr().out


def test_remesh_in_metres_was_read_as_mm_before(tmp_path, roof, capsys):
    """--units m --edge-length 1.5 on a 4 m x 3 m roof: 1.5 m, a handful of faces (read as 1.5 mm it
    asked for about 5.7 million faces and is refused)."""
    src, out = tmp_path / "roof_m.obj", tmp_path / "quads.obj"
    write_mesh(src, roof.mesh)
    assert main(["remesh", str(src), "--units", "m", "--edge-length", "1.5", "-o", str(out), "--optimize",
                 "none"]) == 0
    assert read_mesh(out).n_faces < 20
    assert "(target 1500 mm = 1.5 m)" in capsys.readouterr().out


@pytest.mark.parametrize("command, option, says", [
    ("remesh", "--edge-length", "in --units"),
    ("remesh", "--radius", "in --units"),
    ("offset", "--distances", "in mm whatever --units says"),
])
def test_help_says_the_unit_of_each_length(capsys, command, option, says):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    at = text.index(option, text.index("options:"))
    assert says in text[at:at + 300], text[at:at + 300]


@pytest.mark.parametrize("command", ["remesh", "offset", "measure"])
def test_help_says_a_3dm_file_gives_its_unit(capsys, command):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    assert "a .3dm file's model unit, else mm" in " ".join(capsys.readouterr().out.split())


def test_offset_distances_stay_mm_with_units_m(tmp_path, capsys):
    """Part dimensions are mm in a config and on the command line alike."""
    from optimize.modelling import shapes

    m = shapes.revolution(shapes.dome_profile(radius=8.0, rise=3.0, k=6), 12, name="dome")
    src = tmp_path / "dome_m.obj"
    write_mesh(src, m)
    assert main(["offset", str(src), "--distances=0,-200", "-o", str(tmp_path / "o"), "--units", "m"]) == 0
    layer = read_mesh(tmp_path / "o" / "layer_-200.obj")
    gap = np.linalg.norm(layer.V - 1000.0 * m.V, axis=1)
    assert 150.0 < gap.mean() < 260.0  # about 200 mm along the node axes, not 200 m
