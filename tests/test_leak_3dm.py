"""Memory of a long-lived process (#32): writing and reading .3dm files again and again keeps nothing.

rhino3dm never frees an ``ObjectAttributes`` made in Python, nor a ``File3dmObject``'s geometry and
attributes (which keep the model's own copies alive): one per object was about 3 kB per object per
write and 7 kB per object per read, for good.  The memory measured is the C heap's bytes in use
(glibc ``mallinfo2``: what stays allocated, deaf to page faults and to Python's own arenas), else the
resident size.  Bounds are a fraction of the growth before the fix and far above any noise.
"""
from __future__ import annotations

import ctypes
import gc
import os

import pytest
from cad_fixtures import dome_parts, dome_structure

from fabricate.export import rhino
from fabricate.export.rhino import read_3dm_parts, write_3dm
from optimize.errors import ExportError

import rhino3dm  # noqa: E402 - declared dependency: a missing one fails, never skips


class _MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in
                ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks",
                 "keepcost")]


def _heap_bytes():
    """A function giving the bytes allocated in this process now (C heap in use, or the resident size)."""
    try:
        libc = ctypes.CDLL(None)
        mallinfo2 = libc.mallinfo2
        mallinfo2.restype = _MallInfo2
    except (OSError, AttributeError):
        page = os.sysconf("SC_PAGE_SIZE")

        def rss() -> int:
            with open("/proc/self/statm") as fh:
                return int(fh.read().split()[1]) * page
        return rss

    def in_use() -> int:
        info = mallinfo2()
        return info.uordblks + info.hblkhd
    return in_use


ALLOCATED = _heap_bytes()


def _growth(step, warm: int, rounds: int) -> int:
    """Bytes still allocated after ``rounds`` more calls of ``step`` than after ``warm`` calls."""
    for _ in range(warm):
        step()
    gc.collect()
    before = ALLOCATED()
    for _ in range(rounds):
        step()
    gc.collect()
    return ALLOCATED() - before


def test_writing_a_3dm_twenty_times_keeps_no_memory(tmp_path):
    """Round 5 against round 20 of writing a small model (24 parts, the design mesh, the layers and
    axes): it kept about 95 kB a write (1.4 MB over the 15), now one attributes record a file."""
    parts, structure = dome_parts(4, 2), dome_structure(4, 2)
    path = tmp_path / "model.3dm"
    grown = _growth(lambda: write_3dm(parts, path, structure=structure), warm=5, rounds=15)
    assert grown < 400_000, f"{grown / 1e6:.2f} MB kept by 15 writes"


def test_the_reused_attributes_give_each_object_only_its_own_strings(tmp_path):
    """Every object's attributes come from one reused record: no name, layer or user string of the
    object before it stays on the next (the design mesh has none, an axis only its vertex)."""
    parts, structure = dome_parts(4, 2), dome_structure(4, 2)
    path = tmp_path / "model.3dm"
    write_3dm(parts, path, structure=structure)
    objects = read_3dm_parts(path)
    assert objects["design"]["strings"] == {} and objects["design"]["layer"] == "design mesh"
    assert objects["axis_1"]["strings"] == {"vertex": "0"} and objects["axis_1"]["layer"] == "node axes"
    assert objects["layer_0"]["strings"] == {"distance_mm": "0"}
    panel, beam = parts.panels[0].id, parts.beams[0].id
    assert objects[panel]["layer"] == "glass" and objects[beam]["layer"] == "steel"
    assert objects[panel]["strings"]["kind"] == "panel" and objects[beam]["strings"]["kind"] == "beam"
    assert set(objects[panel]["strings"]) == set(objects[beam]["strings"])


@pytest.fixture(scope="module")
def many_objects(tmp_path_factory):
    """A .3dm of 1,000 small named meshes with a user string each (rhino3dm directly)."""
    path = tmp_path_factory.mktemp("leak") / "many.3dm"
    model, attributes, mesh = rhino3dm.File3dm(), rhino3dm.ObjectAttributes(), rhino3dm.Mesh()
    mesh.Vertices.UseDoublePrecisionVertices = True
    mesh.Vertices.SetCount(8)
    for j in range(8):
        mesh.Vertices.SetPoint3dAt(j, rhino3dm.Point3d(j, j * j, 1.0))
    mesh.Faces.AddFace(0, 1, 2, 3)
    mesh.Faces.AddFace(4, 5, 6, 7)
    attributes.SetUserString("kind", "panel")
    for i in range(1000):
        attributes.Name = f"P{i:04d}"
        model.Objects.AddMesh(mesh, attributes)
    assert model.Write(str(path), 7)
    return path


def test_reading_a_3dm_again_and_again_keeps_no_memory(many_objects):
    """Each read of 1,000 objects kept about 4.5 MB: the file is read in a child process, whose memory
    goes with it."""
    seen = []
    grown = _growth(lambda: seen.append(read_3dm_parts(many_objects)), warm=1, rounds=1)
    assert grown < 1_500_000, f"{grown / 1e6:.2f} MB kept by a read"
    objects = seen[-1]
    assert len(objects) == 1000 and objects["P0007"]["strings"] == {"kind": "panel"}
    assert objects["P0007"]["vertices"].shape == (8, 3) and objects["P0007"]["vertices"][3].tolist() == [3, 9, 1]
    assert str(objects["P0007"]["units"]) == str(rhino3dm.File3dm.Read(str(many_objects)).Settings.ModelUnitSystem)


def test_a_reader_process_that_fails_is_one_line_naming_the_file(many_objects, monkeypatch):
    """The child dies (here: an interpreter that exits 1 at once): the read fails with the file named
    and how the child ended, never a half result or a traceback."""
    monkeypatch.setattr(rhino.sys, "executable", "/bin/false")
    with pytest.raises(ExportError, match=r"many.3dm: rhino3dm could not read the file \(its reader process "
                                          r"ended with exit 1") as info:
        read_3dm_parts(many_objects)
    assert "\n" not in str(info.value)


def test_without_a_child_process_the_file_is_read_here(many_objects, monkeypatch):
    """No interpreter to start (a frozen or sandboxed install): the file is read in this process after all."""
    monkeypatch.setattr(rhino.sys, "executable", "/no/such/python")
    objects = read_3dm_parts(many_objects)
    assert len(objects) == 1000 and objects["P0999"]["strings"] == {"kind": "panel"}


def test_an_unreadable_3dm_is_refused_by_the_reader_process(tmp_path):
    path = tmp_path / "broken.3dm"
    path.write_bytes(b"3D Geometry File Format  not really")
    with pytest.raises(ExportError, match=r"broken.3dm: not a readable .3dm file"):
        read_3dm_parts(path)
