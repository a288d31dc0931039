"""``fabricate measure``: JSON and table output on the real meshes, one-line errors, exit 2."""
import json

import pytest

from fabricate.app.cli import main
from optimize.mesh.io import read_mesh
from optimize.mesh.measures import summary


@pytest.mark.parametrize("which", ["tunnel_path", "cylinder_path"])
def test_measure_prints_json(which, request, capsys):
    path = request.getfixturevalue(which)
    assert main(["measure", str(path)]) == 0
    out = json.loads(capsys.readouterr().out)
    for key in ("planarity", "conical", "circular"):
        assert isinstance(out[key]["max"], float) and isinstance(out[key]["mean"], float)
        assert out[key]["mean"] <= out[key]["max"]
    expected = summary(read_mesh(path))
    assert out["planarity"]["max"] == expected["planarity"]["max"]
    assert out["mesh"]["vertices"] == expected["mesh"]["vertices"]


def test_measure_tunnel_figures(tunnel_path, capsys):
    """The shipped tunnel is left at the design's planarity (3e-5) and is far from conical."""
    assert main(["measure", str(tunnel_path)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["planarity"]["max"] == pytest.approx(3e-5, rel=1e-6)
    assert out["conical"]["max"] > 1.0 and out["conical"]["mean"] > 0.1
    assert out["planarity"]["ok"] is False and out["conical"]["ok"] is False
    assert out["mesh"]["boundary_loops"] == 3 and out["mesh"]["irregular_vertices"] == 8


def test_measure_table(cylinder_path, capsys, monkeypatch):
    monkeypatch.chdir(cylinder_path.parent)  # a short name: the table is not wrapped around a long path
    assert main(["measure", cylinder_path.name, "--table"]) == 0
    out = capsys.readouterr().out
    for word in ("planarity", "conical", "circular", "220 vertices", "vertex types"):
        assert word in out
    with pytest.raises(json.JSONDecodeError):
        json.loads(out)


@pytest.mark.parametrize("name,content,fact", [
    ("bad.obj", "v 0 0 0\nv 1 0 0\nv 1 x 0\nf 1 2 3\n", "bad.obj:3: 'x' is not a number"),
    ("short.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n", "short.off:4: file ends after 2 of 4 vertices"),
    ("mesh.dae", "<COLLADA/>\n", "unknown mesh extension '.dae'"),
    ("mesh.stl", "solid\n", "ASCII STL without any 'vertex' line"),
    ("missing.ply", None, "missing.ply: no such file"),
])
def test_malformed_file_gives_one_line_and_exit_2(tmp_path, capsys, name, content, fact):
    path = tmp_path / name
    if content is not None:
        path.write_text(content)
    assert main(["measure", str(path)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("error: ") and fact in lines[0]
    assert "Traceback" not in captured.err
