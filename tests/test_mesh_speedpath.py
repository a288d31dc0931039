"""The STL and 3MF writers' fast paths: one manifold3d check per parts object, the same bytes as
the plain per-part code."""
import functools

import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.export import meshes, write_3mf, write_stl
from optimize.errors import ExportError


@functools.cache
def rhs_parts():
    """RHS beams (6 plates), tube hubs (tube + 2 caps) and insulated glass with a laminated inner pane."""
    glass = {"type": "insulated", "outer": {"type": "monolithic", "thickness_mm": 10.0}, "cavity_mm": 16.0,
             "inner": {"type": "laminated", "plies_mm": [6.0, 6.0], "interlayer": "PVB", "interlayer_mm": 1.52}}
    return build_parts(dome_structure(n_around=6, k=3),
                       PartSpec(node={"connection": "hub", "hub": "tube", "radius_mm": 90.0, "wall_mm": 8.0, "cap_mm": 12.0},
                                beam={"section": "rhs", "web_mm": 6, "flange_mm": 8, "flange_width_mm": 120},
                                glass=glass))


def _counting(monkeypatch):
    calls = []
    real = meshes.manifold_of

    def counted(X, T):
        calls.append(len(X))
        return real(X, T)

    monkeypatch.setattr(meshes, "manifold_of", counted)
    return calls


def test_the_manifold_check_runs_once_per_parts_and_origin(monkeypatch, tmp_path):
    parts = rhs_parts()
    meshes._CHECKED.pop(parts, None)
    calls = _counting(monkeypatch)
    a = write_stl(parts, tmp_path / "m.stl")["manifold"]
    assert len(calls) == len(parts.groups) and sum(calls) == len(parts)
    write_3mf(parts, tmp_path / "m.3mf")
    b = meshes.validate_manifold(parts)
    assert len(calls) == len(parts.groups)          # the 3MF writer and the third call: no manifold3d
    assert a == b and a is not b and b["components"] == len(parts)
    b["status"] = "changed by the caller"
    assert meshes.validate_manifold(parts)["status"] == "NoError"
    far = meshes.validate_manifold(parts, np.array([1000.0, 0.0, 0.0]))    # another origin: checked again
    assert len(calls) == 2 * len(parts.groups) and far["components"] == len(parts)


def test_a_failed_check_is_not_remembered():
    parts = rhs_parts()
    g = parts.groups[-1]
    bad = type(parts)(groups=parts.groups[:-1] + (_open_group(g),), spec=parts.spec, edge_mode=parts.edge_mode)
    for _ in range(2):
        with pytest.raises(ExportError, match=g.ids[0]):
            meshes.validate_manifold(bad)
    assert not meshes._CHECKED.get(bad)


def _open_group(g):
    """``g`` with its first face left out: every part an open surface."""
    import dataclasses

    return dataclasses.replace(g, faces=g.faces[1:])


def _plain_stl_records(parts, origin):
    """The STL records as the plain code makes them: one float64 soup, ``np.cross``, ``np.linalg.norm``."""
    from fabricate.export.stl import RECORD

    P = meshes.soup(parts, origin)
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    rec = np.zeros(len(P), dtype=RECORD)
    rec["normal"], rec["v"] = n, P
    return rec


@pytest.mark.parametrize("far", [False, True])
def test_stl_records_are_the_bytes_of_the_plain_code(far, tmp_path):
    from fabricate.cad.parts import Parts
    from fabricate.export.stl import read_stl, records

    parts = rhs_parts()
    if far:  # far from the origin: a local origin, vertices relative to it
        import dataclasses

        groups = tuple(dataclasses.replace(g, vertices=g.vertices + [3.0e6, -1.7e6, 2.5e5]) for g in parts.groups)
        parts = Parts(groups=groups, spec=parts.spec, edge_mode=parts.edge_mode)
    origin = parts.local_origin()
    assert np.any(origin) == far
    plain = _plain_stl_records(parts, origin)
    assert records(parts, origin).tobytes() == plain.tobytes()
    write_stl(parts, tmp_path / "m.stl")
    data = (tmp_path / "m.stl").read_bytes()
    assert data[84:] == plain.tobytes() and len(read_stl(tmp_path / "m.stl")[0]) == len(plain)


def test_one_stl_per_part_holds_that_part_of_model_stl(tmp_path):
    from fabricate.export.stl import write_stl_parts

    parts = rhs_parts()
    write_stl(parts, tmp_path / "model.stl")
    facts = write_stl_parts(parts, tmp_path / "stl")
    body = (tmp_path / "model.stl").read_bytes()[84:]
    lo = 0
    for g in parts.groups:
        t = sum(len(f) - 2 for f in g.faces)
        for pid in g.ids:
            data = (tmp_path / "stl" / f"{pid}.stl").read_bytes()
            assert int(np.frombuffer(data, "<u4", 1, 80)[0]) == t and data[84:] == body[lo:lo + 50 * t]
            lo += 50 * t
    assert lo == len(body) and facts["files"] == len(parts) and facts["triangles"] == len(body) // 50
