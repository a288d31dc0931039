"""A disk that refuses a write (#32): every writer fails with one line that says so and names the
file, exit 4, nothing left that looks complete, and the run stops (the cause is the OSError).

Real refusals: under a file size limit (``RLIMIT_FSIZE``, ``SIGXFSZ`` ignored) every write past it
fails with EFBIG in the C library as in Python, rhino3dm's and OpenCASCADE's writers included (they
only return "failed": the C library's errno says why).  A full disk (ENOSPC) is simulated for the
files Python writes: the first write to a file fails.
"""
from __future__ import annotations

import contextlib
import errno
import io
import json
import resource
import signal
from pathlib import Path

import numpy as np
import pytest
from cad_fixtures import dome_mesh, dome_parts

import fabricate.export as export
from fabricate.app.batch import write_csv
from fabricate.app.cli.exits import classify
from fabricate.app.pipeline import RunSummary
from fabricate.app.stages import _write_failed
from fabricate.offset.files import write_axes_obj, write_json
from fabricate.report import html
from fabricate.report.document import write_report_json
from fabricate.report.glb import GlbMesh, write_glb
from fabricate.report.pictures import picture_history
from optimize import atomic
from optimize.errors import ExportError, write_error
from optimize.mesh.io import write_mesh

LIMIT = 512
"""Bytes a file may grow to under :func:`file_size_limit` (every file below is bigger)."""


@contextlib.contextmanager
def file_size_limit(n: int):
    """Every write that would make a file longer than ``n`` bytes fails with EFBIG (this process)."""
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    handler = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (n, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, handler)


@pytest.fixture(scope="module")
def parts():
    return dome_parts(4, 2)


def _glb(path):
    mesh = GlbMesh("m", np.arange(300.0).reshape(-1, 3), np.arange(99).reshape(-1, 3))
    return write_glb(path, [mesh])


def _html(path):
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(html, "render_html", lambda report, pictures, viewer: "<p>" + "report " * 400)
        return html.write_html({}, {}, path, viewer=False)


def _structure_columns(parts, path):
    """The structure's columns added to a bom.csv written before (a check of no beams: they stay empty)."""
    from types import SimpleNamespace

    from fabricate.structure.outputs import add_bom_columns

    check = SimpleNamespace(results=SimpleNamespace(uls=[]), frame=SimpleNamespace(sections=[], ids=[], section_of=[]))
    return add_bom_columns(path, check)


def _csv(path):
    return write_csv([RunSummary(f"job{k}", "ok", 0, message="fine " * 10) for k in range(20)], path)


WRITERS = {  # name: writer of (parts, path)
    "model.stl": lambda p, path: export.write_stl(p, path),
    "stl": lambda p, path: export.write_stl_parts(p, path),
    "model.3dm": lambda p, path: export.write_3dm(p, path),
    "model.3mf": lambda p, path: export.write_3mf(p, path),
    "model.step": lambda p, path: export.write_step(p, path),
    "occ.step": lambda p, path: export.write_step(p, path, engine="occ"),
    "parts.gltf": lambda p, path: export.write_parts_gltf(p, path),
    "outlines.svg": lambda p, path: export.write_svg(p, path),
    "outlines.dxf": lambda p, path: export.write_dxf(p, path),
    "bom.csv": lambda p, path: export.write_bom(p, path),
    "layout_plan.svg": lambda p, path: export.write_layout_plan(p, path),
    "flat.json": lambda p, path: export.write_flat(p, path),
    "glass_schedule.csv": lambda p, path: export.write_glass_schedule(p, path),
    "steel_cut_list.csv": lambda p, path: export.write_steel_cut_list(p, path),
    "node_schedule.csv": lambda p, path: export.write_node_schedule(p, path),
    "nc1": lambda p, path: export.write_nc1(p, path),
    "report.json": lambda p, path: write_report_json({"notes": ["a note"] * 100}, path),
    "report.html": lambda p, path: _html(path),
    "model.glb": lambda p, path: _glb(path),
    "history.png": lambda p, path: picture_history([], path, tolerances={}, title="history"),
    "viewer": lambda p, path: html.copy_viewer(path, b"glb" * 400),
    "batch.csv": lambda p, path: _csv(path),
    "mesh.obj": lambda p, path: write_mesh(path, dome_mesh(8, 4)),
    "mesh.ply": lambda p, path: write_mesh(path, dome_mesh(8, 4)),
    "offset_report.json": lambda p, path: write_json(path, {"notes": ["a note"] * 100}),
    "axes.obj": lambda p, path: write_axes_obj(path, p.mesh.V, p.mesh.V + 1.0),
    "structure bom.csv": lambda p, path: _structure_columns(p, path),
}


def _sizes(path: Path) -> list[int]:
    return [f.stat().st_size for f in ([path] if path.is_file() else path.rglob("*")) if f.is_file()]


@pytest.mark.parametrize("name", list(WRITERS))
def test_a_refused_write_is_one_line_naming_the_file_and_exit_4(name, parts, tmp_path):
    write = WRITERS[name]
    ok = tmp_path / "ok" / name
    if name == "viewer":
        ok.mkdir(parents=True)
    if name == "structure bom.csv":  # the file it rewrites, written without a limit
        export.write_bom(parts, ok)
    write(parts, ok)
    assert min(_sizes(ok)) > LIMIT  # each file it writes is longer than the limit
    target = tmp_path / "full" / name
    target.parent.mkdir()
    if name == "viewer":
        target.mkdir()
    if name == "structure bom.csv":
        export.write_bom(parts, target)
    with file_size_limit(LIMIT), pytest.raises(ExportError) as info:
        write(parts, target)
    text = str(info.value)
    assert text.startswith(f"file too large for the file system writing {target}"), text
    assert "cannot write the " in text and "(File too large" in text and "\n" not in text
    assert info.value.exit_code == 4 and isinstance(info.value.__cause__, OSError)
    assert info.value.__cause__.errno == errno.EFBIG and _write_failed(info.value)  # the run stops there
    assert classify(info.value) == (4, f"error: {text}")
    assert not [p for p in target.parent.rglob("*") if p.is_file() and p.name.endswith(".part")]


class _FullDisk(io.RawIOBase):
    """A file whose every write fails as on a full disk."""

    def writable(self):
        return True

    def write(self, data):
        raise OSError(errno.ENOSPC, "No space left on device")


def _full_open(real_open):
    def opened(file, mode="r", *args, **kwargs):
        fh = real_open(file, mode, *args, **kwargs)
        fh.close()
        raw = io.BufferedWriter(_FullDisk())
        return raw if "b" in mode else io.TextIOWrapper(raw, encoding=kwargs.get("encoding") or "utf-8")
    return opened


@pytest.mark.parametrize("name", ["model.stl", "report.json", "report.html", "batch.csv", "bom.csv"])
def test_a_full_disk_says_so_names_the_file_and_what_it_needed(name, parts, tmp_path, monkeypatch):
    """ENOSPC: ``disk full writing <path>: cannot write the <what> (No space left on device; N MB
    needed, M free there)`` (what was needed when the writer knows it)."""
    write = WRITERS[name]
    monkeypatch.setattr(atomic, "open", _full_open(open), raising=False)
    target = tmp_path / name
    with pytest.raises(ExportError) as info:
        write(parts, target)
    text = str(info.value)
    assert text.startswith(f"disk full writing {target}: cannot write the "), text
    assert "(No space left on device; " in text and text.endswith(" free there)") and "\n" not in text
    if name != "bom.csv":
        assert " needed, " in text
    assert info.value.__cause__.errno == errno.ENOSPC and _write_failed(info.value)
    assert list(tmp_path.iterdir()) == []


def test_the_one_line_of_each_refusal():
    full = write_error("out/model.stl", "STL file", OSError(errno.ENOSPC, "No space left on device"), 12_345_678)
    assert str(full).startswith("disk full writing out/model.stl: cannot write the STL file (No space left on "
                                "device; 12.3 MB needed, ")
    quota = write_error("out/report.json", "report", OSError(errno.EDQUOT, "Disk quota exceeded"), 2000)
    assert str(quota) == ("disk quota exceeded writing out/report.json: cannot write the report (Disk quota "
                          "exceeded; 2.0 kB needed)")
    other = write_error("out/bom.csv", "bill of materials", OSError(errno.EACCES, "Permission denied"))
    assert str(other) == "out/bom.csv: cannot write the bill of materials (Permission denied)"
    assert not _write_failed(other) and all(e.exit_code == 4 for e in (full, quota, other))


def test_a_3dm_rhino3dm_cannot_write_for_another_reason_is_still_one_line(parts, tmp_path, monkeypatch):
    import rhino3dm

    monkeypatch.setattr(rhino3dm.File3dm, "Write", lambda self, path, version: False)
    with pytest.raises(ExportError, match=r"model.3dm: rhino3dm could not write the file$"):
        export.write_3dm(parts, tmp_path / "model.3dm")
    assert list(tmp_path.iterdir()) == []


def test_report_json_written_whole(tmp_path):
    """The report's text is written as it was (the size is measured on the same text)."""
    path = write_report_json({"a": [1, 2.5, None]}, tmp_path / "report.json")
    assert json.loads(path.read_text()) == {"a": [1, 2.5, None]} and path.read_text().endswith("}\n")
