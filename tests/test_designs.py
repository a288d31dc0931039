"""Built-in designs: valid meshes in mm, parameters honoured and checked, the promised
sizes and properties by construction, and the ``fabricate shapes`` command."""
from __future__ import annotations

import inspect

import numpy as np
import pytest

from fabricate.app.cli import main
from optimize import ConfigError
from optimize.mesh import measures
from optimize.modelling.designs import DESIGNS, describe, parse_params
from optimize.modelling.hierarchy import TARGETS, subdivide_and_perturb
from optimize.modelling.strip_analysis import analyze_strip
from optimize.modelling.strips import strip_layouts
from optimize.modelling.subdivision import SCHEMES, subdivide


@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_every_design_builds_in_millimetres(name):
    d = DESIGNS[name]()
    assert d.name == name and d.units == "mm"
    assert d.scheme in SCHEMES and d.target in TARGETS and d.levels >= 0
    assert 1e3 < d.mesh.bbox_diagonal() < 1e6  # metres-scale objects in mm
    assert set(d.params) == set(inspect.signature(DESIGNS[name]).parameters)
    assert d.mesh.n_faces > 0 and d.description


@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_noise_is_seeded(name):
    a, b = DESIGNS[name](noise=0.05, seed=3), DESIGNS[name](noise=0.05, seed=3)
    c, clean = DESIGNS[name](noise=0.05, seed=4), DESIGNS[name]()
    assert np.array_equal(a.mesh.V, b.mesh.V)
    assert not np.allclose(a.mesh.V, c.mesh.V) and not np.allclose(a.mesh.V, clean.mesh.V)
    assert np.array_equal(a.mesh.F, clean.mesh.F)


@pytest.mark.parametrize("name, kw", [("dome", {}), ("dome", {"meridians": 7, "rings": 3}),
                                      ("torus_patch", {}), ("torus_patch", {"sweep_deg": 360.0})])
def test_surfaces_of_revolution_are_pq_conical_and_circular(name, kw):
    m = DESIGNS[name](**kw).mesh
    assert measures.planarity(m).max() < 1e-12
    assert measures.conical_defect(m).max() < 1e-9 and measures.conical_defect(m).size > 0
    assert measures.circular_defect(m).max() < 1e-9
    noisy = DESIGNS[name](noise=0.05, **kw).mesh
    assert measures.planarity(noisy).max() > 1e-3


def test_hypar_grids():
    para = DESIGNS["hypar_roof"]().mesh
    assert measures.planarity(para).max() < 1e-12  # a translational net
    rul = DESIGNS["hypar_roof"](grid_kind="rulings").mesh
    assert measures.planarity(rul).max() > 1e-2
    # both on a saddle z = c x y: rulings over the square, parabolas over its 45-degree turn
    V = rul.V
    assert np.allclose(V[:, 2], 4 * 3000.0 * V[:, 0] * V[:, 1] / 12000.0 ** 2)
    V = para.V
    assert np.allclose(V[:, 2], 16 * 3000.0 * V[:, 0] * V[:, 1] / 12000.0 ** 2)


def test_railway_station_sizes():
    d = DESIGNS["railway_station"]()
    assert d.mesh.n_faces == 40 and d.levels == 3  # 10 x 4 control quads
    fine, _ = subdivide(d.mesh, d.scheme, d.levels)
    assert 2000 <= fine.n_vertices <= 6000
    big = DESIGNS["railway_station"](nu=15, nv=6).mesh
    fine, _ = subdivide(big, "catmull_clark", 3)
    assert 5500 <= fine.n_vertices <= 6500  # the size of the paper's conical benchmark


def test_trefoil_band_is_a_moebius_band_of_336_quads():
    d = DESIGNS["trefoil_band"]()
    assert not d.mesh.topology.orientable and len(d.mesh.topology.boundary_loops) == 1
    fine, _ = subdivide(d.mesh, d.scheme, d.levels)
    assert fine.n_faces == 336
    (lay,) = strip_layouts(fine)
    assert lay.closed and lay.twist and not fine.topology.orientable
    two_sided = DESIGNS["trefoil_band"](twist=False).mesh
    assert two_sided.topology.orientable and len(two_sided.topology.boundary_loops) == 2


def _ruling_lengths(mesh):
    return [np.linalg.norm(mesh.V[lay.b] - mesh.V[lay.a], axis=1) for lay in strip_layouts(mesh)]


def test_two_sided_trefoil_band_lies_on_the_rectifying_developable():
    """Rulings along the Darboux vector: the band's normals are the knot's principal normals and it
    is nearly developable already, so the strip optimizer keeps its width (a band across the
    principal normals shrank to 20 mm rulings and folded its glass)."""
    r = 42
    d = DESIGNS["trefoil_band"](twist=False, rulings=r)
    assert measures.planarity(d.mesh).max() < 0.01
    t = 2 * np.pi * (np.arange(r) + 0.5) / r  # quad i lies between rulings i and i + 1
    def knot(t):
        return np.stack([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)], 1)

    h = 1e-4  # principal normal by central differences, independent of the design's formulas
    d1, d2 = (knot(t + h) - knot(t - h)) / (2 * h), (knot(t + h) - 2 * knot(t) + knot(t - h)) / h ** 2
    T = d1 / np.linalg.norm(d1, axis=1, keepdims=True)
    N = d2 - np.sum(d2 * T, axis=1, keepdims=True) * T
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    normals = measures.face_normals(d.mesh)[strip_layouts(d.mesh)[0].faces]
    assert np.degrees(np.arccos(np.abs(np.sum(normals * N, axis=1)))).max() < 5.0
    out = subdivide_and_perturb(d.mesh, 1, scheme="chaikin", target="strip")
    (lengths,) = _ruling_lengths(out.mesh)
    assert out.success and lengths.min() > 0.5 * 500.0  # across the principal normals: 40 mm


def test_developable_strips_start_nearly_developable_with_the_singular_curve_outside():
    d = DESIGNS["developable_strips"]()
    assert measures.planarity(d.mesh).max() < 0.02
    for lay in strip_layouts(d.mesh):
        a = analyze_strip(d.mesh, lay)
        t = np.concatenate([a.t, a.s])
        t = t[np.isfinite(t)]
        assert np.all((t < -0.5) | (t > 1.5))  # rulings meet well outside the strip
    ruling = d.mesh.V[1] - d.mesh.V[0]  # first ruling of strip 0: centre line z = 1000 sin(2 pi x / 8000)
    t = np.array([1.0, 0.0, 1000.0 * 2 * np.pi / 8000.0])
    t /= np.linalg.norm(t)
    assert np.linalg.norm(ruling - (ruling @ t) * t) == pytest.approx(1200.0, rel=1e-12)  # `width` across
    assert np.degrees(np.arccos(np.linalg.norm(ruling - (ruling @ t) * t) / np.linalg.norm(ruling))) > 20.0
    out = subdivide_and_perturb(DESIGNS["developable_strips"](count=2).mesh, 1, scheme="chaikin",
                                target="strip")
    assert out.success
    for lengths in _ruling_lengths(out.mesh):  # the optimizer keeps the strips' width
        assert lengths.min() > 0.9 * 1200.0


def test_developable_strips_refuse_a_turn_no_developable_strip_can_make():
    with pytest.raises(ConfigError, match=r"turn_deg=60.*amplitude=500.*leaning \d+ deg"):
        DESIGNS["developable_strips"](turn_deg=60.0, amplitude=500.0)
    with pytest.raises(ConfigError, match="amplitude"):
        DESIGNS["developable_strips"](turn_deg=10.0, amplitude=0.0)
    flat = DESIGNS["developable_strips"](turn_deg=0.0, amplitude=0.0).mesh
    assert measures.planarity(flat).max() < 1e-12


def test_developable_strips_are_separate_strips():
    d = DESIGNS["developable_strips"](count=3)
    assert len(strip_layouts(d.mesh)) == 3 and d.mesh.topology.n_components == 3


@pytest.mark.parametrize("name, kw, match", [
    ("railway_station", {"nu": 1}, "nu=1"),
    ("railway_station", {"length": -5.0}, "length"),
    ("dome", {"rings": 2.5}, "rings"),
    ("hypar_roof", {"grid_kind": "diagonal"}, "grid_kind"),
    ("torus_patch", {"minor": 20000.0}, "minor"),
    ("trefoil_band", {"width": 5000.0}, "width"),
    ("freeform_canopy", {"noise": float("nan")}, "noise"),
])
def test_bad_parameters_name_the_key(name, kw, match):
    with pytest.raises(ConfigError, match=match):
        DESIGNS[name](**kw)


def test_describe_and_parse_params():
    items = {d["name"]: d for d in describe()}
    assert set(items) == set(DESIGNS)
    params = {p["name"]: p for p in items["railway_station"]["params"]}
    assert params["nu"]["default"] == 10 and params["nu"]["help"]
    assert all(p["help"] for d in items.values() for p in d["params"])
    got = parse_params("trefoil_band", ["rulings=30", "twist=no", "width=400"])
    assert got == {"rulings": 30, "twist": False, "width": 400.0}
    with pytest.raises(ConfigError, match="int"):
        parse_params("dome", ["meridians=many"])
    with pytest.raises(ConfigError, match="unknown parameter"):
        parse_params("dome", ["colour=red"])


def test_cli_lists_and_writes(tmp_path, capsys):
    assert main(["shapes"]) == 0
    out = capsys.readouterr().out
    assert all(name in out for name in DESIGNS) and "mm" in out
    path = tmp_path / "dome.obj"
    assert main(["shapes", "dome", "-o", str(path), "--param", "meridians=12"]) == 0
    from optimize.mesh.io import read_mesh

    back = read_mesh(path)
    ref = DESIGNS["dome"](meridians=12).mesh
    assert np.array_equal(back.V, ref.V) and np.array_equal(back.F, ref.F)
    assert main(["shapes", "dome", "--param", "meridians=x"]) == 2
    assert main(["shapes", "nosuch"]) == 2
    refined = tmp_path / "rs.obj"
    assert main(["shapes", "railway_station", "-o", str(refined), "--refined", "--param", "levels=1"]) == 0
    assert read_mesh(refined).n_faces == 160
