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
