"""The STL and 3MF writers' fast paths: one manifold3d check per parts object, the same bytes as
the plain per-part code."""
import functools

import numpy as np
import pytest
from cad_fixtures import dome_structure

from fabricate.cad import PartSpec, build_parts
from fabricate.cad.geometry import volumes
from fabricate.cad.parts import Parts
from fabricate.export import meshes, write_3mf, write_stl
from fabricate.export.threemf import g12_words
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


def _far(parts):
    """``parts`` moved far from the origin (a local origin, vertices written relative to it)."""
    import dataclasses

    groups = tuple(dataclasses.replace(g, vertices=g.vertices + [3.0e6, -1.7e6, 2.5e5]) for g in parts.groups)
    return Parts(groups=groups, spec=parts.spec, edge_mode=parts.edge_mode)


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
    assert calls == [1] * len(parts.groups)         # one part of each group: the others have its triangles
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


def test_one_part_per_group_checks_what_every_part_would():
    """manifold3d on each part alone: the status and genus of the first part of a group, and the
    numpy volumes of the triangles against manifold3d's, part by part."""
    parts = rhs_parts()
    for g in parts.groups:
        X, T = meshes.group_triangles(g, parts.local_origin())
        ms = [meshes.manifold_of(X[i:i + 1], T) for i in range(len(g))]
        assert {m.status().name for m in ms} == {"NoError"} and len({m.genus() for m in ms}) == 1
        vol = volumes(X, g.faces)                          # what validate_manifold sums
        np.testing.assert_allclose(vol, [m.volume() for m in ms], rtol=1e-10)   # both rounded sums
        np.testing.assert_allclose(vol, g.volume_mm3, rtol=1e-10)


def _writers():
    from fabricate.export import write_step
    from fabricate.export.ifc import write_ifc
    from fabricate.export.rhino import write_3dm

    return {"validate": lambda parts, out: meshes.validate_manifold(parts), "stl": write_stl, "3mf": write_3mf,
            "step": write_step, "ifc": write_ifc, "3dm": write_3dm}


@pytest.mark.parametrize("writer, value", [(w, np.nan) for w in ("validate", "stl", "3mf", "step", "ifc", "3dm")]
                         + [("validate", np.inf), ("validate", -np.inf)])   # one guard: nan in each writer
def test_a_part_with_a_vertex_that_is_not_finite_is_named_and_no_file_is_written(value, writer, tmp_path):
    import dataclasses

    parts = rhs_parts()
    g = parts.groups[1]
    V = g.vertices.copy()
    V[len(g) - 1, 2, 0] = value
    bad = type(parts)(groups=parts.groups[:1] + (dataclasses.replace(g, vertices=V),) + parts.groups[2:],
                      spec=parts.spec, edge_mode=parts.edge_mode)
    out = tmp_path / f"model.{writer}"
    with pytest.raises(ExportError, match=f"{g.ids[-1]}: a vertex is not a finite number"):
        _writers()[writer](bad, out)
    assert list(tmp_path.iterdir()) == []


def _open_group(g):
    """``g`` with its first face left out: every part an open surface."""
    import dataclasses

    return dataclasses.replace(g, faces=g.faces[1:])


def _plain_stl_records(parts, origin):
    """The STL records as the plain code makes them: one float64 soup, ``np.cross``, ``np.linalg.norm``."""
    from fabricate.export.stl import RECORD

    P = _soup(parts, origin)
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    rec = np.zeros(len(P), dtype=RECORD)
    rec["normal"], rec["v"] = n, P
    return rec


@pytest.mark.parametrize("far", [False, True])
def test_stl_records_are_the_bytes_of_the_plain_code(far, tmp_path):
    from fabricate.export.stl import read_stl, records

    parts = _far(rhs_parts()) if far else rhs_parts()
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


def _g12_texts(x):
    sign, text = g12_words(x)
    raw = np.concatenate([sign.reshape(-1, 1), text.reshape(-1, 3).view(np.uint8)], axis=1)
    return [bytes(r[r != 0]) for r in raw]


def test_g12_words_are_percent_12g_of_hostile_numbers():
    rng = np.random.default_rng(7)
    special = [0.0, -0.0, 0.5, 1.5, 2.5, 1.0, -1.0, 1e11, 1e12, 999999999999.5, 999999999999.4, 99999999999.95,
               9.9999999999995, 0.000099999999999995, 0.0001, 0.00001, 0.001234, 123456789012.5, 1e-300, 5e-324,
               1e300, np.inf, -np.inf, np.nan, 1 / 3, 2 / 3, 1000.0, 12345.5, -12345.5, 0.1, 0.2, 0.3, 2.0 ** 40]
    powers = 10.0 ** np.arange(-7, 15)
    n = rng.integers(10 ** 11, 10 ** 12, 4000) + 0.5                      # 12-digit mantissas and a half ...
    d = rng.choice([-3e-4, -2e-4, -1.5e-4, -1e-4, -5e-5, 5e-5, 1e-4, 1.5e-4, 2e-4, 3e-4], 4000)  # ... or near it
    near_half = (n + d) * 10.0 ** rng.integers(-15, 1, 4000).astype(float)
    x = np.concatenate([
        special, powers, -powers, np.nextafter(powers, 0), np.nextafter(powers, np.inf),
        rng.uniform(-40000, 40000, 20000),                                    # model coordinates (mm)
        rng.standard_normal(20000) * 10.0 ** rng.integers(-9, 17, 20000),       # every exponent
        np.round(rng.uniform(-1e5, 1e5, 5000), 7) + 5e-8,                      # near halves at the 12th digit
        rng.integers(-10 ** 6, 10 ** 6, 5000) + 0.5, rng.uniform(-1, 1, 5000), rng.uniform(-1e-3, 1e-3, 2000),
        near_half])
    assert _g12_texts(x) == [b"%.12g" % v for v in x.tolist()]
    X = rng.uniform(-9000, 9000, (4, 5, 3))
    sign, text = g12_words(X)
    assert sign.shape == (4, 5, 3) and text.shape == (4, 5, 3, 3)


def _plain_model(parts, origin):
    """``3D/3dmodel.model``'s objects as the plain per-part code writes them (``%.12g`` of each vertex)."""
    from fabricate.cad.parts import KINDS
    from fabricate.export.meshes import group_triangles

    extra = sorted({g.material for g in parts.groups if g.material})
    out, object_id = [], 2
    for g in parts.groups:
        X, T = group_triangles(g, origin)
        tris = ("<triangles>" + "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in T.tolist())
                + "</triangles></mesh></object>\n")
        pindex = len(KINDS) + extra.index(g.material) if g.material else KINDS.index(g.kind)
        for pid, V in zip(g.ids, X):
            out.append(f'<object id="{object_id}" name="{pid}" type="model" pid="1" pindex="{pindex}"><mesh>'
                       "<vertices>" + "".join('<vertex x="%.12g" y="%.12g" z="%.12g"/>' % tuple(v) for v in V)  # noqa: UP031
                       + "</vertices>" + tris)
            object_id += 1
    return "".join(out).encode()


@pytest.mark.parametrize(("block", "far"), [(None, False), (7, False), (None, True)])
def test_3mf_model_is_the_text_of_the_plain_code(block, far, tmp_path, monkeypatch):
    import zipfile

    from fabricate.export import threemf

    if block:  # a few parts at a time: the blocks join into the same text
        monkeypatch.setattr(threemf, "BLOCK", block)
    parts = _far(rhs_parts()) if far else rhs_parts()
    assert np.any(parts.local_origin()) == far
    facts = write_3mf(parts, tmp_path / "m.3mf")
    with zipfile.ZipFile(tmp_path / "m.3mf") as z:
        model = z.read("3D/3dmodel.model")
    objects = model[model.index(b"<object "):model.index(b"</resources>")]
    assert objects == _plain_model(parts, parts.local_origin())
    tail = model[model.index(b"</resources>"):].decode()
    assert tail.count("<item objectid=") == facts["objects"] == len(parts)
    assert f'<item objectid="{len(parts) + 1}"' in tail and facts["triangles"] == sum(
        len(g) * sum(len(f) - 2 for f in g.faces) for g in parts.groups)


def _soup(parts, origin: np.ndarray) -> np.ndarray:
    """(T, 3, 3) float64: every triangle of every part, relative to ``origin``, part order (the plain
    reference the STL writer's per-group records are held to)."""
    out = [X[:, T].reshape(-1, 3, 3) for X, T in (meshes.group_triangles(g, origin) for g in parts.groups)]
    return np.concatenate(out) if out else np.zeros((0, 3, 3))
