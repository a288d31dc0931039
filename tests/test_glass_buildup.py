"""Glass build-ups (issue 18 item 4): monolithic, laminated, insulated units as one solid per ply."""
from __future__ import annotations

import csv
import functools

import numpy as np
import pytest

from cad_fixtures import dome_structure
from optimize.errors import ConfigError

LAMINATED = {"type": "laminated", "plies_mm": [8, 8], "interlayer": "PVB", "interlayer_mm": 1.52}
INSULATED = {"type": "insulated", "outer": {"type": "monolithic", "thickness_mm": 10}, "cavity_mm": 16,
             "gas": "argon", "inner": {"type": "laminated", "plies_mm": [6, 6], "interlayer_mm": 1.52},
             "edge_seal_mm": 14}


@functools.lru_cache(maxsize=None)
def parts_of(glass_key: str, edge: str = "auto", step: float = 0.0):
    from fabricate.cad import PartSpec, build_parts

    glass = {"mono": None, "lam": LAMINATED, "igu": dict(INSULATED, step_mm=step)}[glass_key]
    return build_parts(dome_structure(n_around=6, k=3), PartSpec(glass=glass, edge=edge, joint_gap=10.0))


def panel_groups(parts) -> dict[str, list]:
    out: dict[str, list] = {}
    for g in parts.of_kind("panel"):
        out.setdefault(g.member, []).append(g)
    return out


def test_build_up_texts_thickness_and_layer_offsets():
    from fabricate.cad.glass import BuildUp

    lam = BuildUp.from_config(LAMINATED)
    assert lam.short() == "88.4" and lam.describe() == "laminated 88.4 (8 + 1.52 PVB + 8)"
    assert lam.thickness_mm == pytest.approx(17.52)
    igu = BuildUp.from_config(INSULATED)
    assert igu.short() == "10/16/66.4"
    assert "16 argon" in igu.describe() and "edge seal 14" in igu.describe()
    layers = igu.layers()
    assert [ly.member for ly in layers] == ["outer pane", "cavity", "inner ply 1", "inner interlayer 1",
                                            "inner ply 2"]
    assert [ly.solid for ly in layers] == [True, False, True, True, True]
    # stacked without gaps from the bearing face (offset 0, on the beams) outward
    assert layers[-1].offset_mm == 0.0
    for below, above in zip(layers[1:], layers[:-1]):
        assert above.offset_mm == pytest.approx(below.offset_mm + below.thickness_mm)
    assert layers[0].offset_mm + layers[0].thickness_mm == pytest.approx(igu.thickness_mm) == 10 + 16 + 13.52
    sgp = BuildUp.from_config({"type": "laminated", "plies_mm": [10, 10, 10], "interlayer": "SGP",
                               "interlayer_mm": 1.52})
    assert sgp.short() == "10 + 1.52 SGP + 10 + 1.52 SGP + 10"


def test_monolithic_default_is_todays_panel():
    from fabricate.cad import PartSpec

    mono = parts_of("mono")
    assert [g.member for g in mono.of_kind("panel")] == [""] * len(mono.of_kind("panel"))
    assert mono.panels[0].id == "P0001" and PartSpec().glass.describe() == "monolithic 10 mm"
    assert PartSpec(glass={"type": "monolithic", "thickness_mm": 12}).glass_thickness == 12.0


def test_one_solid_per_ply_with_ids_outside_in():
    parts = parts_of("igu")
    members = panel_groups(parts)
    assert list(members) == ["outer pane", "inner ply 1", "inner interlayer 1", "inner ply 2"]
    for k, (member, gs) in enumerate(members.items()):
        for g in gs:
            assert all(i.endswith(f".{k + 1}") for i in g.ids)
            assert g.material == ("PVB" if "interlayer" in member else "")
    # only the ply on the beams touches them; the beams carry that ply
    bearing = members["inner ply 2"][0]
    assert any(n.startswith("B") for n in bearing.neighbours[0])
    assert not any(n.startswith("B") for n in members["outer pane"][0].neighbours[0])
    assert members["outer pane"][0].neighbours[0] == ()                   # across the cavity: nothing
    beam = parts.of_kind("beam")[0]
    assert all(n.endswith(".4") for n in beam.neighbours[0] if n.startswith("P"))


@pytest.mark.parametrize("edge", ["perpendicular", "axis"])
def test_plies_are_parallel_slabs_at_their_offsets(edge):
    """Every ply's two faces are parallel to the bearing face, at the build-up's distances from it on
    the glass side (away from the beams); in axis mode every ply's sides lie in the same planes."""
    from fabricate.cad.glass import BuildUp

    parts = parts_of("igu", edge)
    members = panel_groups(parts)
    solids = BuildUp.from_config(INSULATED).solids()
    ref = members["inner ply 2"][0]
    n_b = ref.normals[:, ref.outline_face]                             # outward at the bearing face
    o_b = np.einsum("pi,pi->p", n_b, ref.vertices[:, ref.faces[ref.outline_face][0]])
    glass_side = -n_b                                                  # the bearing face looks at the beams
    for layer, g in zip(solids, (gs[0] for gs in members.values())):
        for face, dist in ((g.outline_face, layer.offset_mm), (g.bevel_face, layer.offset_mm + layer.thickness_mm)):
            n = g.normals[:, face]
            assert np.abs(np.abs(np.einsum("pi,pi->p", n, n_b)) - 1).max() < 1e-12      # parallel
            h = np.einsum("pki,pi->pk", g.vertices[:, list(g.faces[face])], glass_side) + o_b[:, None]
            np.testing.assert_allclose(h, dist, atol=1e-9)
        if edge == "axis":
            side = slice(2, None)
            np.testing.assert_allclose(g.normals[:, side], ref.normals[:, side], atol=1e-12)


def test_volumes_add_up_to_the_unit():
    """A laminate sliced into plies and interlayers fills exactly the monolithic panel of its thickness."""
    from fabricate.cad import PartSpec, build_parts

    lam = parts_of("lam")
    whole = build_parts(dome_structure(n_around=6, k=3), PartSpec(glass_thickness=17.52, joint_gap=10.0))
    per_face = np.zeros(whole.mesh.n_faces)
    for g in lam.of_kind("panel"):
        np.add.at(per_face, g.element, g.volume_mm3)
    mono = np.zeros_like(per_face)
    for g in whole.of_kind("panel"):
        np.add.at(mono, g.element, g.volume_mm3)
    np.testing.assert_allclose(per_face, mono, rtol=1e-9)


def test_stepped_inner_pane_is_set_in_and_must_bear():
    from fabricate.cad import PartSpec

    step = 5.0
    parts = parts_of("igu", "perpendicular", step)
    members = panel_groups(parts)
    outer, inner = members["outer pane"][0], members["inner ply 2"][0]
    side = slice(2, None)
    np.testing.assert_allclose(inner.normals[:, side], outer.normals[:, side], atol=1e-12)
    off = lambda g: np.einsum("pfi,pfi->pf", g.normals[:, side],  # noqa: E731
                              g.vertices[:, [f[0] for f in g.faces[2:]]])
    np.testing.assert_allclose(off(outer) - off(inner), step, atol=1e-9)
    assert parts.report["beams"]["bearing_width_mm"] == pytest.approx(0.5 * (60.0 - 10.0) - step)
    with pytest.raises(ConfigError, match="parts.glass.step_mm = 25 mm: the inner pane would not bear"):
        PartSpec(glass=dict(INSULATED, step_mm=25.0), beam_width=60.0, joint_gap=10.0)


def test_glass_schedule_one_row_per_unit_weight_from_thickness_area_density(tmp_path):
    """Perpendicular sides: every ply is a right prism of the bearing outline, so the unit weighs
    area x (sum of ply thickness x density)."""
    from fabricate.export import write_glass_schedule

    parts = parts_of("igu", "perpendicular")
    facts = write_glass_schedule(parts, tmp_path / "glass_schedule.csv")
    rows = list(csv.DictReader(open(tmp_path / "glass_schedule.csv", encoding="utf-8")))
    assert len(rows) == facts["rows"] == parts.mesh.n_faces
    per_m2 = (10 + 12) * 2500 * 1e-3 + 1.52 * 1070 * 1e-3             # kg/m2 of glass and PVB
    for r in rows:
        assert r["build_up"].startswith("insulated 10/16/66.4") and r["spacer_setback_mm"] == "14"
        assert float(r["thickness_mm"]) == pytest.approx(39.52)
        assert r["solids"] == " ".join(f"{r['id']}.{k}" for k in (1, 2, 3, 4))
        assert float(r["weight_kg"]) == pytest.approx(float(r["area_m2"]) * per_m2, abs=0.06)
        assert "." not in r["neighbours"] and "." not in r["id"]


def test_config_build_ups_and_one_line_errors(tmp_path):
    from _pipeline_fixtures import tiny_config
    from fabricate.cad import PartSpec

    cfg = tiny_config(tmp_path, parts={"glass": INSULATED})
    spec = PartSpec(**cfg.parts.model_dump())
    assert spec.glass.short() == "10/16/66.4"
    assert spec.glass_thickness == pytest.approx(22 + 1.52 * 1070 / 2500)   # the structure's glass load
    bad = {
        "unknown type": ({"glass": {"type": "tempered"}}, ["parts.glass.type", "'tempered'", "laminated"]),
        "one ply": ({"glass": {"type": "laminated", "plies_mm": [8]}}, ["parts.glass.plies_mm", "two or more"]),
        "plies on monolithic": ({"glass": {"type": "monolithic", "thickness_mm": 8, "plies_mm": [4, 4]}},
                                ["parts.glass.plies_mm", "laminated"]),
        "no inner pane": ({"glass": {"type": "insulated", "outer": {"type": "monolithic", "thickness_mm": 8}}},
                          ["parts.glass.inner", "expected a pane"]),
        "cavity on laminated": ({"glass": dict(LAMINATED, cavity_mm=16)}, ["parts.glass.cavity_mm", "insulated"]),
        "two build-ups": ({"glass_thickness": 8, "glass": LAMINATED}, ["parts.glass_thickness = 8", "parts.glass"]),
        "thin ply": ({"glass": {"type": "laminated", "plies_mm": [8, 1]}}, ["parts.glass.plies_mm[1] = 1"]),
        "unknown interlayer": ({"glass": dict(LAMINATED, interlayer="EVA")}, ["parts.glass.interlayer", "'EVA'"]),
    }
    for case, (parts, fragments) in bad.items():
        with pytest.raises(ConfigError) as err:
            tiny_config(tmp_path, parts=parts)
        message = str(err.value)
        assert message.count("\n") == 0, (case, message)
        for fragment in fragments:
            assert fragment in message, (case, fragment, message)
    # the shorthand and a consistent monolithic section agree
    same = tiny_config(tmp_path, parts={"glass_thickness": 8, "glass": {"type": "monolithic", "thickness_mm": 8}})
    assert PartSpec(**same.parts.model_dump()).glass.describe() == "monolithic 8 mm"


def test_files_of_a_build_up_read_back_and_pass_the_check(tmp_path):
    """STEP, 3MF, STL, IFC, 3dm, flat.json, DXF, schedules, cut files of an insulated roof: every ply a
    solid with its id, the file check passes (volumes against the BOM, bearing, no clash, flat rebuild)."""
    import ifcopenshell

    from fabricate import export
    from fabricate.check import check_outputs
    from fabricate.app.config_parts import NestingSection
    from fabricate.export.step_text import read_step_text
    from fabricate.export.threemf import read_3mf
    from fabricate.app.stages import EXPORTS

    parts = parts_of("igu")
    structure = dome_structure(n_around=6, k=3)
    for key, fname, fn in EXPORTS:
        if key != "gltf":
            getattr(export, fn)(parts, tmp_path / fname, **({"structure": structure} if key == "rhino" else {}))
    cut = export.write_cut_files(parts, tmp_path, NestingSection().model_dump())
    ids = {p.id for p in parts}
    assert {f"P0001.{k}" for k in (1, 2, 3, 4)} <= ids
    solids, _ = read_step_text(tmp_path / "model.step")
    assert set(solids) == ids
    assert set(read_3mf(tmp_path / "model.3mf")) == ids
    vol = {p.id: p.volume_mm3 for p in parts}
    for name, s in solids.items():
        assert s["volume_mm3"] == pytest.approx(vol[name], rel=1e-9)
    result = check_outputs(tmp_path)
    failed = {k: v for k, v in result["checks"].items() if isinstance(v, dict) and v.get("pass") is not True}
    assert not failed, failed
    # IFC: one plate per unit, four face sets, the layer set lists plies, interlayer and cavity
    f = ifcopenshell.open(str(tmp_path / "model.ifc"))
    plates = {p.Name: p for p in f.by_type("IfcPlate")}
    assert set(plates) == {f"P{i:04d}" for i in range(1, 13)}
    assert len(plates["P0001"].Representation.Representations[0].Items) == 4
    layer_set = f.by_type("IfcMaterialLayerSet")[0]
    assert [(ly.Material.Name, ly.LayerThickness) for ly in layer_set.MaterialLayers] == [
        ("Glass", 10.0), ("Argon", 16.0), ("Glass", 6.0), ("PVB", 1.52), ("Glass", 6.0)]
    # cut files: one per ply thickness, the interlayers are not cut from glass sheet
    glass = {k: v for k, v in cut.items() if k.startswith("cut_glass") and k.endswith(".dxf")}
    assert set(glass) == {"cut_glass_10mm.dxf", "cut_glass_6mm.dxf"}
    count = {k: v["layout"]["parts"] + len(v["oversize"]) for k, v in glass.items()}  # nested + listed oversize
    assert count == {"cut_glass_6mm.dxf": 24, "cut_glass_10mm.dxf": 12}
    assert all(i.endswith((".2", ".4")) for i in glass["cut_glass_6mm.dxf"]["oversize"])
    bom = list(csv.DictReader(open(tmp_path / "bom.csv", encoding="utf-8")))
    pvb = [r for r in bom if r["material"] == "PVB"]
    assert len(pvb) == 12 and all(r["unit"] + ".3" == r["id"] and r["member"] == "inner interlayer 1" for r in pvb)
    assert all(float(r["weight_kg"]) == pytest.approx(float(r["volume_mm3"]) * 1070e-9, abs=1e-3) for r in pvb)


def test_shipped_configs_use_overhead_build_ups():
    from pathlib import Path

    from fabricate.cad import PartSpec
    from fabricate.app.config import load_config

    configs = Path(__file__).resolve().parents[1] / "configs"
    types = {}
    for name in ("atrium_roof", "railway_station", "dome", "freeform_canopy", "halftunnel", "quickstart"):
        spec = PartSpec(**load_config(configs / f"{name}.yaml").parts.model_dump())
        types[name] = spec.glass
    assert types["atrium_roof"].type == "insulated" and types["atrium_roof"].inner.laminated
    assert types["railway_station"].type == "laminated"
    assert all(b.type != "monolithic" for n, b in types.items() if n != "quickstart")


def test_shop_limits_flag_a_unit_once_by_its_id():
    from fabricate.cad import PartSpec, build_parts

    spec = PartSpec(glass=INSULATED, joint_gap=10.0, limits={"min_corner_deg": 80.0, "max_panel_kg": 100.0})
    parts = build_parts(dome_structure(n_around=6, k=3), spec)
    lim = parts.report["limits"]
    assert lim["corner"]["count"] == 12 and lim["corner"]["ids"] == sorted(set(lim["corner"]["ids"]))
    assert all("." not in i for key in ("corner", "weight") for i in lim[key]["ids"])
    per_unit = {}
    for g in parts.of_kind("panel"):
        for i, v in zip(g.ids, g.volume_mm3 * spec.group_density(g) * 1e-9):
            per_unit[i.split(".")[0]] = per_unit.get(i.split(".")[0], 0.0) + v
    assert set(lim["weight"]["ids"]) == {u for u, kg in per_unit.items() if kg > 100.0}


def test_occ_step_engine_names_every_ply(tmp_path):
    from fabricate.export.step import write_step
    from fabricate.export.step_read import read_step

    parts = parts_of("lam")
    write_step(parts, tmp_path / "m.step", engine="occ")
    named, _ = read_step(tmp_path / "m.step")
    assert sorted(n for n, _ in named) == sorted(p.id for p in parts)
    assert {"P0001.1", "P0001.2", "P0001.3"} <= {n for n, _ in named}


def test_a_ply_that_cannot_be_built_names_itself_and_the_build_up():
    """A unit far too thick for its panels in axis mode (sides leaning in): the outer ply folds and the
    error names that ply, the build-up and what to change, in one line."""
    from cad_fixtures import dome_mesh
    from fabricate.cad import PartSpec, build_parts
    from fabricate.cad.errors import PartError
    from fabricate.offset import offset_structure

    thick = {"type": "insulated", "outer": {"type": "laminated", "plies_mm": [25, 25, 25, 25], "interlayer_mm": 10},
             "cavity_mm": 50, "inner": {"type": "laminated", "plies_mm": [25, 25, 25], "interlayer_mm": 10}}
    # a 0.8 m dome with the glass inside (flip): the axes converge on the glass side
    s = offset_structure(dome_mesh(8, 4, radius_m=0.4, rise_m=0.16), (0.0, -100.0), flip=True)
    with pytest.raises(PartError) as err:  # a part that cannot be built: bad input (exit 2) at its face
        build_parts(s, PartSpec(glass=thick, edge="axis", joint_gap=10.0, beam_width=60.0))
    message = str(err.value)
    assert err.value.part == "P0024.1" or err.value.part.endswith(".1")
    assert "\n" not in message and ".1 (element" in message and "outer ply 1 lies 250 to 275 mm" in message
    assert "(parts.glass)" in message and "parts.edge: perpendicular" in message


def test_the_config_as_run_loads_again_with_its_build_up(tmp_path):
    """config.yaml of a run (defaults filled in) is a valid config: with parts.glass the shorthand
    glass_thickness is left out of it."""
    from _pipeline_fixtures import tiny_config
    from fabricate.cad import PartSpec
    from fabricate.app.config import parse_config

    cfg = tiny_config(tmp_path, parts={"glass": INSULATED})
    data = cfg.as_dict()
    assert "glass_thickness" not in data["parts"]
    again = parse_config(data, source=tmp_path / "config.yaml")
    assert PartSpec(**again.parts.model_dump()).glass == PartSpec(**cfg.parts.model_dump()).glass
    mono = tiny_config(tmp_path, parts={"glass_thickness": 8})
    assert mono.as_dict()["parts"]["glass_thickness"] == 8 and mono.as_dict()["parts"]["glass"] is None


def test_3mf_gives_the_interlayer_a_material_of_its_own(tmp_path):
    import re
    import zipfile

    from fabricate.export.threemf import write_3mf

    write_3mf(parts_of("lam"), tmp_path / "m.3mf")
    model = zipfile.ZipFile(tmp_path / "m.3mf").read("3D/3dmodel.model").decode()
    bases = re.findall(r'<base name="([^"]+)"', model)
    assert bases[-1] == "PVB interlayer"
    pindex = dict(re.findall(r'name="(P\d+\.\d)" type="model" pid="1" pindex="(\d)"', model))
    assert pindex["P0001.2"] == str(len(bases) - 1) and bases[int(pindex["P0001.1"])] == "glass"


# -- the glass order's vocabulary (issue 36 item 1) -----------------------------------------------------
def test_overhead_defaults_per_ply_and_surface_numbers():
    from fabricate.cad.glass import BuildUp

    igu = BuildUp.from_config(INSULATED)
    plies = igu.plies()
    assert [p.treatment for p in plies] == ["toughened-heat-soaked", "heat-strengthened", "heat-strengthened"]
    assert [p.surfaces for p in plies] == [(1, 2), (3, 4), (5, 6)] and [p.pane for p in plies] == ["outer", "inner",
                                                                                                    "inner"]
    assert plies[0].coatings == ((2, "solar-control"),) and all(p.edge == "smooth-ground" for p in plies)
    assert (igu.spacer, igu.spacer_colour, igu.secondary_seal, igu.gas_fill_pct) == ("warm-edge", "black",
                                                                                     "silicone", 90.0)
    assert igu.overhead_warnings() == [] and igu.standards() == ["EN 14179-1", "EN 1863-1", "EN ISO 12543-2",
                                                                 "EN 1279-5"]
    given = BuildUp.from_config(dict(INSULATED, coatings={"#3": "low-E"}, spacer="TPS", gas_fill_pct=85,
                                     outer={"type": "monolithic", "thickness_mm": 10, "treatment": "toughened",
                                            "edge_work": "polished"},
                                     inner=dict(INSULATED["inner"], treatment=["float", "heat-strengthened"])))
    assert [p.treatment for p in given.plies()] == ["toughened", "float", "heat-strengthened"]
    assert given.plies()[1].coatings == ((3, "low-E"),) and given.plies()[0].describe() == \
        "10 mm toughened, edge polished (KPO)"
    assert BuildUp.from_config(given.as_config()) == given                            # the config as run reloads


def test_a_monolithic_pane_overhead_is_warned_by_unit_id():
    from fabricate.cad import PartSpec, build_parts
    from fabricate.cad.glass import BuildUp
    from fabricate.report.measures import warnings

    assert "DIN 18008-2" in BuildUp.from_config(None).overhead_warnings()[0]
    assert "little residual strength" in BuildUp.from_config(
        dict(LAMINATED, treatment="toughened")).overhead_warnings()[0]
    mono = build_parts(dome_structure(n_around=6, k=3), PartSpec())
    over = mono.report["limits"]["overhead"]
    steep = [g for g in mono.of_kind("panel")][0]
    tilt = np.degrees(np.arcsin(np.abs(steep.normals[:, steep.outline_face, 2])))
    assert over["ids"] == [i for i, t in zip(steep.ids, tilt) if t > 10.0] and over["count"] == 12
    assert any("overhead limit" in w and "P0001" in w for w in warnings({}, mono.report["limits"]))
    assert "overhead" not in parts_of("lam").report["limits"]                         # laminated: no warning


@pytest.mark.parametrize("glass, words", [
    (dict(LAMINATED, treatment="tempered"), ["parts.glass.treatment", "'tempered'", "toughened-heat-soaked"]),
    (dict(LAMINATED, treatment=["float"]), ["parts.glass.treatment", "a list of 2 (one per ply)"]),
    (dict(LAMINATED, edge_work="as-cut", treatment="toughened"), ["edge_work = as-cut", "EN 12150-1"]),
    (dict(LAMINATED, coatings={5: "low-E"}), ["parts.glass.coatings", "surface 5", "1 .. 4"]),
    (dict(LAMINATED, spacer="TPS"), ["parts.glass.spacer", "insulated unit"]),
    (dict(INSULATED, gas_fill_pct=120), ["parts.glass.gas_fill_pct", "[0, 100] %"]),
    (dict(INSULATED, spacer_colour=""), ["parts.glass.spacer_colour", "colour name"]),
])
def test_bad_glass_order_words_name_the_key(glass, words):
    from fabricate.cad.glass import BuildUp

    with pytest.raises(ConfigError) as err:
        BuildUp.from_config(glass)
    assert all(w in str(err.value) for w in words), str(err.value)


def test_the_config_takes_the_vocabulary():
    from fabricate.app.config import RunConfig

    glass = dict(INSULATED, coatings={3: "low-E"}, spacer_colour="grey", secondary_seal="polysulphide",
                 inner=dict(INSULATED["inner"], edge_work=["ground", "polished"]))
    cfg = RunConfig.model_validate({"input": {"shape": {"name": "dome"}}, "parts": {"glass": glass}})
    unit = cfg.parts.to_options().glass
    assert [p.edge for p in unit.plies()] == ["smooth-ground", "ground", "polished"]
    assert unit.coatings == ((3, "low-E"),) and unit.secondary_seal == "polysulphide"
    again = RunConfig.model_validate({"input": {"shape": {"name": "dome"}}, "parts": {"glass": unit.as_config()}})
    assert again.parts.to_options().glass == unit
