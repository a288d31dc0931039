"""Flat data of every part cut from sheet: the outline thickened, bevelled and placed is the solid."""
import numpy as np
import pytest
from cad_fixtures import dome_structure
from scipy.spatial import ConvexHull, HalfspaceIntersection

from fabricate.cad import PartSpec, build_parts
from fabricate.cad.parts import cut_from_sheet
from fabricate.cad.flat import corner_triples, cut_planes, face_planes, solid_from_flat
from fabricate.cad.geometry import polygon_area_2d, volumes
from fabricate.export.flatdata import check_flat, read_flat, rebuild, write_flat
from fabricate.export import write_bom
from fabricate.offset import offset_structure
from optimize.modelling import shapes


def _twisted():
    a = np.stack([np.linspace(0, 6000, 5), np.zeros(5), 2000 * np.sin(np.linspace(0, 2, 5))], axis=1)
    b = np.stack([np.zeros(4), np.linspace(0, 4500, 4), 2000 * np.cos(np.linspace(0, 2, 4))], axis=1)
    return offset_structure(shapes.translational(a, b), (0.0, -200.0))


CASES = {"dome": lambda: build_parts(dome_structure(), PartSpec()),
         "dome_hubs": lambda: build_parts(dome_structure(n_around=6, k=3), PartSpec(node_radius=60.0)),
         "dome_tube_hubs": lambda: build_parts(dome_structure(n_around=6, k=3), PartSpec(node={
             "connection": "hub", "hub": "tube", "radius_mm": 80.0, "wall_mm": 8.0, "cap_mm": 12.0})),
         "open_flipped": lambda: build_parts(dome_structure(n_around=6, k=3, flip=True, sweep=np.pi), PartSpec()),
         "twisted": lambda: build_parts(_twisted(), PartSpec())}


@pytest.fixture(scope="module", params=sorted(CASES))
def parts(request):
    return CASES[request.param]()


def _flat_groups(parts):
    return [g for g in parts.groups if cut_from_sheet(g.kind, g.member)]


def test_every_part_cut_from_sheet_has_flat_data_hub_caps_included():
    parts = CASES["dome_tube_hubs"]()
    flat = {g.member for g in _flat_groups(parts) if g.kind == "node"}
    assert flat == {"top cap", "bottom cap"}                     # the tube is ordered as a section
    for g in _flat_groups(parts):
        if g.kind == "node":  # a cap: a 12 mm plate, its outline the 24-gon of radius 80, square edges
            np.testing.assert_allclose(g.thickness_mm, 12.0)
            np.testing.assert_allclose(np.linalg.norm(g.flat - g.flat.mean(axis=1, keepdims=True), axis=2), 80.0,
                                       rtol=1e-9)
            np.testing.assert_allclose(g.bevel_deg, 0.0, atol=1e-9)


def test_flat_data_rebuild_every_solid(parts):
    for g in _flat_groups(parts):
        N, O = face_planes(g.bevel_ref, g.bevel_ref_z, g.bevel_deg, g.thickness_mm, g.cuts, len(g.faces),
                           g.outline_face, g.bevel_face, g.transform)
        X = solid_from_flat(N, O, corner_triples(g.faces, N), g.ring, g.bevel_ref, g.bevel_ref_z, g.transform)
        np.testing.assert_allclose(volumes(X, g.faces), g.volume_mm3, rtol=1e-9)
        assert np.linalg.norm(X - g.vertices, axis=2).max() < 1e-6  # mm; same faces: a Hausdorff bound


def test_convex_parts_equal_the_halfspace_intersection_qhull_finds(parts):
    """Independent of the face list: where every edge is a ridge or one bevel, the part is the sheet slab
    cut by the bevel planes; qhull finds its corners and volume."""
    for g in _flat_groups(parts):
        n, o = cut_planes(g.bevel_ref, g.bevel_ref_z, g.bevel_deg)
        k = g.flat.shape[1]
        for i in range(min(len(g), 12)):  # a sample of each group: qhull per part
            if np.any(g.bevel_deg[i] < -1e-9) and g.kind == "beam":
                continue  # a valley (groove) is not convex
            H = np.concatenate([n[i].reshape(-1, 3), -o[i].reshape(-1, 1)], axis=1)
            H = np.concatenate([H, [[0, 0, 1, 0], [0, 0, -1, -g.thickness_mm[i]]]])
            inside = np.append(g.bevel_ref[i].mean(axis=0), -0.5 * g.thickness_mm[i])
            X = HalfspaceIntersection(H, inside).intersections
            M = g.transform[i]
            local = (g.vertices[i] - M[:3, 3]) @ M[:3, :3]
            assert ConvexHull(X).volume == pytest.approx(g.volume_mm3[i], rel=1e-9)
            d = np.linalg.norm(X[:, None] - local[None], axis=2)
            assert max(d.min(axis=0).max(), d.min(axis=1).max()) < 1e-6
            assert k == len(g.bevel_deg[i])


def test_transform_is_rigid_and_the_sheet_holds_the_part(parts):
    for g in _flat_groups(parts):
        R = g.transform[:, :3, :3]
        np.testing.assert_allclose(np.einsum("pji,pjk->pik", R, R), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
        np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
        local = np.einsum("pji,pvj->pvi", R, g.vertices - g.transform[:, None, :3, 3])
        assert local[..., 2].max() < 1e-9 and local[..., 2].min() > -g.thickness_mm.max() - 1e-9
        # the stock rectangle holds every corner and the cut outline
        assert local[..., :2].min() > -1e-9 and np.all(local[..., :2].max(axis=1) <= g.rect + 1e-9)
        assert g.flat.min() > -1e-9 and np.all(g.flat.max(axis=1) <= g.rect + 1e-9)
        assert np.all(g.rect[:, 0] >= g.rect[:, 1])


def test_the_cut_outline_holds_every_corner_seen_from_above(parts):
    for g in _flat_groups(parts):
        local = np.einsum("pji,pvj->pvi", g.transform[:, :3, :3], g.vertices - g.transform[:, None, :3, 3])[..., :2]
        Q = g.flat
        E = np.roll(Q, -1, axis=1) - Q
        # left of every edge of the counter-clockwise outline (cross product >= 0)
        cross = (E[:, :, None, 0] * (local[:, None, :, 1] - Q[:, :, None, 1])
                 - E[:, :, None, 1] * (local[:, None, :, 0] - Q[:, :, None, 0]))
        L = np.linalg.norm(E, axis=2)[..., None]
        assert (cross / L).min() > -1e-6
        assert np.all(polygon_area_2d(Q) > 0)


def test_beam_outline_reaches_the_node_axes_and_the_glass_ridge():
    """The issue's defect: the outline stopped short of the node axis.  Now the outline corners are the
    beam quad's corners (on the node axes), and its length is the beam's full length."""
    parts = CASES["dome"]()
    g = parts.of_kind("beam")[0]
    M = g.transform
    corners = np.einsum("pij,pkj->pki", M[:, :3, :3], np.concatenate([g.bevel_ref, g.bevel_ref_z[..., None]], 2))
    corners += M[:, None, :3, 3]
    np.testing.assert_allclose(corners, g.vertices[:, :4], atol=1e-9)
    assert np.all(g.rect[:, 0] >= g.length_mm - 1e-9)
    # a ridge under the glass between two panels (positive bevels both sides); one plane at the boundary
    two = np.array([sum(n[0] == "P" for n in nb) == 2 for nb in g.neighbours])
    assert two.any() and (~two).any()
    assert np.all(g.bevel_deg[two, 0] > 0)
    np.testing.assert_allclose(g.bevel_deg[~two, 0, 0], -g.bevel_deg[~two, 0, 1], atol=1e-9)
    ends = g.bevel_deg[:, [1, 3]]  # V ends in the bisector planes; a square end where no neighbour is
    assert ends.min() > -1e-9 and (ends > 1).mean() > 0.5


def test_flat_json_round_trip_and_check(parts, tmp_path):
    write_flat(parts, tmp_path / "flat.json")
    write_bom(parts, tmp_path / "bom.csv")
    from fabricate.export.bom import read_bom

    groups = read_flat(tmp_path / "flat.json")
    by_id = parts.by_id
    for g in groups:
        X = rebuild(g)
        V = np.stack([by_id[i].vertices for i in g["ids"]])
        assert np.linalg.norm(X - V, axis=2).max() < 1e-6
    res = check_flat(tmp_path / "flat.json", read_bom(tmp_path / "bom.csv"))
    assert res["pass"] and res["parts"] == sum(len(g) for g in _flat_groups(parts))


def test_a_wrong_bevel_in_flat_json_fails_the_check(tmp_path):
    import json

    from fabricate.export.bom import read_bom
    from fabricate.export.threemf import read_3mf
    from fabricate.export import write_3mf
    from fabricate.export.verify import Solid

    parts = CASES["dome_hubs"]()
    for name, fn in (("flat.json", write_flat), ("bom.csv", write_bom), ("model.3mf", write_3mf)):
        fn(parts, tmp_path / name)
    meshes = {k: Solid(k, V, T) for k, (V, T) in read_3mf(tmp_path / "model.3mf").items()}
    bom = read_bom(tmp_path / "bom.csv")
    assert check_flat(tmp_path / "flat.json", bom, meshes=meshes)["pass"]
    doc = json.loads((tmp_path / "flat.json").read_text())
    doc["groups"][-1]["bevel_deg"][0][0][0] += 1.0  # one degree off on one edge of one beam
    (tmp_path / "flat.json").write_text(json.dumps(doc))
    res = check_flat(tmp_path / "flat.json", bom, meshes=meshes)
    assert not res["pass"] and res["failures"][0]["id"] == doc["groups"][-1]["ids"][0]


def test_hausdorff_of_all_parts_at_once_equals_one_at_a_time():
    """check_flat's batched Hausdorff bound (parts grouped by corner count, face loops with repeated
    corners) gives what one part at a time on the distinct corners gives."""
    from fabricate.export.flatdata import _hausdorff, _hausdorff_all

    rng = np.random.default_rng(4)
    X = rng.normal(size=(9, 8, 3)) * 100
    corners = [None if i == 4 else X[i][rng.integers(0, 8, 24 if i % 2 else 30)] + rng.normal(size=3) * 1e-3
               for i in range(9)]
    got = _hausdorff_all(X, corners)
    assert got[4] is None
    for i, B in enumerate(corners):
        if B is not None:
            assert got[i] == _hausdorff(X[i], np.unique(B, axis=0))
            assert got[i] > 1e-4
