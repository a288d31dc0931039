"""Issue 32 / 30: a tiny remesh edge length is refused before anything grows with it (exit 2, one
line naming the value, its unit, the faces it implies and the smallest edge length allowed)."""
from __future__ import annotations

import math
import re
import tracemalloc

import pytest
import yaml

from fabricate.app.cli import main
from optimize.errors import ConfigError
from optimize.mesh.io import write_mesh
from optimize.remesh import surfaces
from optimize.remesh.quads import MAX_FACES, check_remesh_size, remesh, remesh_size


@pytest.fixture(scope="module")
def roof():
    """A 4 x 3 height field (about 12.9 square units), 216 triangles."""
    return surfaces.height_field(size=(4.0, 3.0), n=(13, 10))


def test_the_estimate_is_the_face_count_made(roof):
    quads = remesh(roof.mesh, 0.5, side=roof.side)
    size = remesh_size(roof.mesh, 0.5)
    assert size.ok and 0.85 < quads.n_faces / size.faces < 1.15, (quads.n_faces, size.faces)
    assert size.area == pytest.approx(12.9, rel=0.02)


@pytest.mark.parametrize("h", [1e-7, 1e-4])
def test_a_tiny_edge_length_is_refused_before_allocating(roof, h):
    tracemalloc.start()
    try:
        with pytest.raises(ConfigError) as info:
            remesh(roof.mesh, h, side=roof.side)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 20 * 2 ** 20, f"peak {peak / 2 ** 20:.0f} MiB"  # 16 GiB before the guard
    message = str(info.value)
    assert info.value.exit_code == 2 and len(message.splitlines()) == 1
    faces = remesh_size(roof.mesh, h).faces
    assert f"edge_length {h:.4g}" in message and f"{faces:,.3g} faces" in message, message
    smallest = float(re.search(r"at least ([\d.e+-]+)", message).group(1))
    assert smallest == pytest.approx(math.sqrt(remesh_size(roof.mesh, h).area / MAX_FACES), rel=2e-3)
    assert check_remesh_size(roof.mesh, smallest).faces <= MAX_FACES  # the value named is accepted


def test_the_limit_follows_the_address_space_limit(roof):
    """Under ``ulimit -v`` the limit is the faces that fit in half of it (checked in a child)."""
    import multiprocessing as mp

    ctx = mp.get_context("fork")
    q = ctx.Queue()
    p = ctx.Process(target=_capped_limit, args=(roof.mesh, q))
    p.start()
    p.join(60)
    limit, message = q.get(timeout=5)
    assert p.exitcode == 0
    assert limit < MAX_FACES and "GiB this process may use" in message, (limit, message)


def _capped_limit(mesh, q) -> None:
    import resource

    with open("/proc/self/statm") as fh:
        size = int(fh.read().split()[0]) * resource.getpagesize()
    resource.setrlimit(resource.RLIMIT_AS, (size + 512 * 2 ** 20, resource.RLIM_INFINITY))
    size = remesh_size(mesh, 1.0)
    try:
        check_remesh_size(mesh, math.sqrt(size.area / (size.limit + 10)))
        q.put((size.limit, "accepted"))
    except ConfigError as exc:
        q.put((size.limit, str(exc)))


def test_remesh_command_refuses_a_tiny_edge_length_in_its_unit(tmp_path, roof, capsys):
    src, out = tmp_path / "roof_m.obj", tmp_path / "quads.obj"
    write_mesh(src, roof.mesh)  # metres
    code = main(["remesh", str(src), "--units", "m", "--edge-length", "1e-7", "-o", str(out), "--optimize", "none"])
    err = capsys.readouterr().err
    assert code == 2, err
    line = err.strip()
    assert len(line.splitlines()) == 1 and "Traceback" not in line
    assert "--edge-length 1e-07 m makes about 1.29e+15 faces" in line, line
    assert "area 12.88 m2" in line and f"more than the {MAX_FACES:,}" in line, line
    assert "at least 0.00254 m" in line, line
    assert not out.exists()


def test_remesh_help_names_the_limit(capsys):
    with pytest.raises(SystemExit):
        main(["remesh", "--help"])
    assert f"{MAX_FACES:,} faces" in " ".join(capsys.readouterr().out.split())


@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf", "x"])
def test_remesh_command_refuses_a_length_that_is_not_positive(tmp_path, roof, capsys, value):
    src = tmp_path / "roof.obj"
    write_mesh(src, roof.mesh)
    with pytest.raises(SystemExit) as info:
        main(["remesh", str(src), f"--edge-length={value}", "-o", str(tmp_path / "q.obj")])
    assert info.value.code == 2
    assert "expected a length > 0" in capsys.readouterr().err


def test_run_refuses_a_tiny_input_edge_length(tmp_path, roof, capsys):
    src = tmp_path / "roof.obj"
    write_mesh(src, roof.mesh)
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text(yaml.safe_dump({"input": {"surface": str(src), "edge_length": 1e-7, "side": list(roof.side)},
                                   "units": "m"}))
    code = main(["run", str(cfg), "--out", str(tmp_path / "out"), "-q"])
    err = capsys.readouterr().err
    assert code == 2, err
    assert "input.edge_length 1e-07 m makes" in err and "1.29e+15 faces" in err and "at least 0.00254 m" in err, err
    assert not (tmp_path / "out" / "tiny").exists()
