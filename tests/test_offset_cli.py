"""``fabricate offset``: files, round trips, refusals, exit codes, atomic output folder."""
from __future__ import annotations

import json

import numpy as np
import pytest

from fabricate.app.cli import main
from fabricate.offset import offset_structure
from optimize.modelling import shapes
from optimize.mesh.io import read_mesh, write_mesh
from optimize.mesh.measures import planarity


@pytest.fixture
def dome_file(tmp_path):
    m = shapes.revolution(shapes.dome_profile(radius=8000.0, rise=3000.0, k=6), 12, name="dome")
    path = tmp_path / "dome.obj"
    write_mesh(path, m)
    return path


@pytest.fixture
def translational_file(tmp_path):
    u = np.linspace(0.0, 1.0, 7)
    a = np.stack([6000 * u, 0 * u, 1500 * np.sin(2 * u)], axis=1)
    b = np.stack([0 * u, 5000 * u, 900 * np.cos(2.5 * u)], axis=1)
    path = tmp_path / "trans.off"
    write_mesh(path, shapes.translational(a, b))
    return path


@pytest.fixture
def noisy_file(tmp_path):
    m = shapes.perturbed(shapes.revolution(shapes.dome_profile(8000.0, 3000.0, 6), 12), 0.02, seed=9)
    path = tmp_path / "noisy.obj"
    write_mesh(path, m)
    return path


def test_conical_mesh_writes_every_file_and_layers_round_trip(dome_file, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["offset", str(dome_file), "--distances", "0,20,120", "-o", str(out)]) == 0
    stdout = capsys.readouterr().out
    assert "status: conical" in stdout
    names = {p.name for p in out.iterdir()}
    assert names == {"layer_0.obj", "layer_20.obj", "layer_120.obj", "axes.obj", "axes.json",
                     "beams.obj", "beams.json", "focal.json", "offset_report.json", ".conical-fab-run.json"}
    mesh = read_mesh(dome_file)
    s = offset_structure(mesh, (0, 20, 120))
    for i, text in enumerate(("0", "20", "120")):
        layer = read_mesh(out / f"layer_{text}.obj")
        assert np.array_equal(layer.F, mesh.F)
        assert np.array_equal(layer.V, s.layers[i])  # %.17g: exact
    report = json.loads((out / "offset_report.json").read_text())
    assert report["status"] == "conical" and report["distances_mm"] == [0.0, 20.0, 120.0]
    assert report["input"]["path"] == str(dome_file)
    assert report["files"]["layers"] == {"0": "layer_0.obj", "20": "layer_20.obj", "120": "layer_120.obj"}
    beams = json.loads((out / "beams.json").read_text())
    np.testing.assert_array_equal(np.array(beams["quads"]), s.beam_quads)
    bm = read_mesh(out / "beams.obj")
    assert bm.n_faces == len(s.edges)
    np.testing.assert_array_equal(bm.V, s.beam_quads.reshape(-1, 3))
    axes = json.loads((out / "axes.json").read_text())
    np.testing.assert_array_equal(np.array(axes["axes"]), s.axes)
    focal = json.loads((out / "focal.json").read_text())
    assert len(focal["focal"]["points"]) == len(s.edges) and set(focal["focal"]["family"]) == {0, 1}
    assert max(focal["spherical_image"]["circular_defect_rad"]) <= 1e-9
    lines = [ln for ln in (out / "axes.obj").read_text().splitlines() if ln.startswith("l ")]
    assert len(lines) == mesh.n_vertices and lines[0] == "l 1 2"


def test_distance_text_is_kept_in_file_names_and_flip(dome_file, tmp_path):
    out = tmp_path / "flip"
    assert main(["offset", str(dome_file), "--distances=-20, 0 ,120.0", "-o", str(out), "--flip"]) == 0
    assert {"layer_-20.obj", "layer_0.obj", "layer_120.0.obj"} <= {p.name for p in out.iterdir()}
    mesh = read_mesh(dome_file)
    s = offset_structure(mesh, (-20, 0, 120), flip=True)
    np.testing.assert_array_equal(read_mesh(out / "layer_-20.obj").V, s.layers[0])
    assert json.loads((out / "offset_report.json").read_text())["flip"] is True


def test_pq_but_not_conical_proceeds_and_says_so(translational_file, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["offset", str(translational_file), "--distances", "0,50", "-o", str(out)]) == 0
    stdout = capsys.readouterr().out
    assert "NOT CONICAL" in stdout and "twist" in stdout and "mm" in stdout
    report = json.loads((out / "offset_report.json").read_text())
    assert report["status"] == "pq_not_conical" and not report["is_conical"]
    assert report["beams"]["max_twist_mm"] > 0.01 and report["face_distance"]["max_spread_mm"] > 0
    assert report["beams"]["worst"][0]["twist_mm"] == report["beams"]["max_twist_mm"]


def test_non_pq_mesh_is_refused_with_the_worst_faces_and_nothing_written(noisy_file, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["offset", str(noisy_file), "--distances", "0,20", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    p = planarity(read_mesh(noisy_file))
    assert f"worst face {int(np.argmax(p))} " in err and "not planar" in err and "--force" in err
    assert not out.exists()
    # --force: written, marked, exit 3
    assert main(["offset", str(noisy_file), "--distances", "0,20", "-o", str(out), "--force"]) == 3
    report = json.loads((out / "offset_report.json").read_text())
    assert report["status"] == "not_pq" and report["input"]["forced"] is True
    assert report["planarity"]["worst"][0]["face"] == int(np.argmax(p))
    assert "NOT PQ" in capsys.readouterr().out


@pytest.mark.parametrize("text, pattern", [("0,x,120", "item 2 'x'"), ("0,20,20", "repeats"),
                                           ("0,,5", "item 2 ''"), ("nan", "not a finite")])
def test_bad_distances_exit_2(dome_file, tmp_path, capsys, text, pattern):
    assert main(["offset", str(dome_file), f"--distances={text}", "-o", str(tmp_path / "o")]) == 2
    assert pattern in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_output_folder_is_atomic_and_a_foreign_folder_is_not_replaced(dome_file, tmp_path, capsys,
                                                                      monkeypatch):
    """-o DIR follows the run-folder rules: a marker, --replace to replace, never a foreign file."""
    from fabricate.app.runfolder import MARKER

    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("keep me")
    assert main(["offset", str(dome_file), "--distances", "0,20", "-o", str(foreign), "--replace"]) == 2
    assert (foreign / "thesis.tex").read_text() == "keep me"
    assert "is not a run folder of conical-fab" in capsys.readouterr().err
    out = tmp_path / "out"
    assert main(["offset", str(dome_file), "--distances", "0,20", "-o", str(out)]) == 0
    assert (out / MARKER).is_file()
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    # an earlier offset output is replaced only when asked
    assert main(["offset", str(dome_file), "--distances", "0,5,10", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "holds an earlier run" in err and "rerun with --replace" in err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    # ... as a whole, and only when the new one is complete
    import fabricate.offset.files as files

    def broken(path, data):
        raise OSError("disk full")

    with monkeypatch.context() as m:
        m.setattr(files, "write_json", broken)
        with pytest.raises(OSError):
            main(["--debug", "offset", str(dome_file), "--distances", "0,5,10", "-o", str(out), "--replace"])
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
    assert main(["offset", str(dome_file), "--distances", "0,5,10", "-o", str(out), "--replace"]) == 0
    assert (out / "layer_10.obj").is_file() and not (out / "layer_20.obj").exists()
    # a file a person added is never replaced, --replace or not
    (out / "notes.txt").write_text("mine")
    assert main(["offset", str(dome_file), "--distances", "0,20", "-o", str(out), "--replace"]) == 2
    assert "notes.txt (added)" in capsys.readouterr().err and (out / "notes.txt").read_text() == "mine"
