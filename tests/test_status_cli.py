"""The status a command prints agrees with the measures it prints (issue 32): far from the origin,
near the end of float64, scaled beyond any building, slivers and straight corners."""
import json
import warnings


from fabricate.app.cli import main
from optimize.mesh import Mesh, measures
from optimize.mesh.io import read_mesh, write_mesh
from optimize.modelling import shapes


def _saddle(name="saddle") -> Mesh:
    """4 x 4 quads of 1 m on a saddle, shaken: the default method makes it PQ in a few iterations."""
    g = shapes.grid(5, 5, size=(4000.0, 4000.0), height=lambda x, y: 1e-4 * (x * x - y * y))
    return shapes.perturbed(g, 0.05, seed=3, name=name)


def _optimize(tmp_path, mesh, capsys, *extra):
    src, out, rep = tmp_path / "in.obj", tmp_path / "out.obj", tmp_path / "r.json"
    write_mesh(src, mesh)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # a leaked overflow fails the command
        code = main(["optimize", str(src), "-o", str(out), "--report", str(rep), *extra])
    cap = capsys.readouterr()
    report = json.loads(rep.read_text()) if rep.exists() else None
    return code, cap.out, cap.err, report, out


def test_far_from_the_origin_the_status_agrees_with_the_printed_measures(tmp_path, capsys):
    """1e14 mm from the origin float64 holds the coordinates to 1/64 mm, 1.5e-5 of an edge: the
    solver's scaled iterate is planar to 1e-10, the written mesh only to 6e-6.  The run said
    'NOT reached' over the figures and 'every tolerance reached', exit 0, under them."""
    mesh = _saddle()
    code, out, _, report, _ = _optimize(tmp_path, mesh, capsys)
    assert code == 0 and "NOT reached" not in out  # the same mesh at the origin: reached
    far = mesh.with_vertices(mesh.V + 1e14)
    code, out, err, report, written = _optimize(tmp_path, far, capsys)
    assert code == 3, out + err
    assert "planarity" in out and "NOT reached" in out
    assert "every tolerance reached" not in out and "converged" not in out
    assert report["success"] is False and report["tolerance_reached"] is False and report["status"] == "stalled"
    assert report["defects"]["planarity"]["ok"] is False
    assert "float64" in report["message"] and "near the origin" in report["message"]
    assert "NOT CONVERGED" in written.read_text().splitlines()[1]
    # the measure is the written mesh's own: it reads the same centred (exact differences)
    res = read_mesh(written)
    centred = measures.planarity(res, res.V - res.V.mean(axis=0)).max()
    assert centred == report["defects"]["planarity"]["max"] > 1e-6


def test_coordinates_near_1e307_are_refused_in_one_line(tmp_path, capsys):
    mesh = _saddle()
    huge = mesh.with_vertices(mesh.V / 4000.0 * 1e307)
    code, out, err, report, written = _optimize(tmp_path, huge, capsys)
    assert code == 2, err
    assert "RuntimeWarning" not in err and len(err.strip().splitlines()) == 1, err
    assert "coordinates up to 1.0" in err and "e+307 mm" in err and "overflow float64" in err
    assert "expected |x| <= 1e+150 mm" in err
    assert report is None and not written.exists()


def test_measure_near_the_largest_float64_says_only_what_is_beyond_it(tmp_path, capsys):
    """Edges of 7.5e307 mm have a mean float64 holds (it once said 'beyond float64', after a raw
    RuntimeWarning of the sum); the diagonal and the areas are beyond it, and said so."""
    mesh = shapes.grid(3, 3, size=(1.0, 1.0))
    src = tmp_path / "big.obj"
    write_mesh(src, mesh.with_vertices(mesh.V * 1.5e308))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        assert main(["measure", str(src)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["edge_length"] == {"min": 7.5e307, "max": 7.5e307, "mean": 7.5e307}
    beyond = sorted(n.split(" is ")[0] for n in out["notes"])
    assert beyond == ["face_area.max", "face_area.mean", "face_area.min", "mesh.bbox_diagonal"]


def test_a_mesh_scaled_beyond_any_building_is_not_blamed_on_narrow_faces(tmp_path, capsys):
    """Scaled by 1e15 (coordinates up to 2e18 mm) float64 holds positions to 256 mm: the 10 mm glass
    and the joint gap vanish in rounding, so no panel builds.  The message said the faces were
    too narrow; it names the coordinates and the range."""
    mesh = _saddle()
    src, cfg = tmp_path / "big.obj", tmp_path / "big.yaml"
    write_mesh(src, mesh.with_vertices(mesh.V * 1e15))
    cfg.write_text("name: big\ninput:\n  mesh: big.obj\noptimize:\n  target: pq\noutputs: {step: false, "
                   "stl: false, 3mf: false, ifc: false, 3dm: false, nc1: false, gltf: false, pictures: false, "
                   "html: false, dxf: false, svg: false, check: off}\n")
    code = main(["run", str(cfg), "--out", str(tmp_path / "out"), "-q"])
    cap = capsys.readouterr()
    text = cap.out + cap.err
    assert code == 2  # refused at the input, before optimizing (it ended 3 after the CAD stage failed)
    assert "narrow" not in text, text
    assert "big.obj: coordinates up to 4.09e+18 mm: float64 holds them only to 512 mm" in text, text
    assert "expected |x| < 4.5e+12 mm" in text and "is the unit right?" in text
    assert not (tmp_path / "out" / "big").exists()


def _flat_grid_with(vertex: int, position) -> Mesh:
    g = shapes.grid(5, 5, size=(4000.0, 4000.0))
    V = g.V.copy()
    V[vertex] = position
    return g.with_vertices(V)


def test_a_sliver_quad_is_degenerate_never_converged(tmp_path, capsys):
    """Face 0 of a flat grid with its corner vertex 1.5e-6 mm from its neighbour (1.5e-9 of the
    1 m edges): planar, so the run 'converged' at once and exit 0; a quad with such a side is a
    triangle."""
    g = shapes.grid(5, 5, size=(4000.0, 4000.0))
    mesh = _flat_grid_with(0, g.V[1] + [0.0, -1.5e-6, 0.0])
    code, out, err, report, _ = _optimize(tmp_path, mesh, capsys)
    assert code == 3, out + err
    assert report["status"] == "degenerate" and report["success"] is False
    assert report["defects"]["shrunk_edges"] == {"count": 1, "edges": 1, "faces": [0]}
    assert report["defects"]["straight_corners"]["count"] == 0
    assert "degenerate faces: 1 with a shrunk edge, 0 with a straight corner (first [0])" in out
    assert "every tolerance reached" not in out


def test_a_quad_with_a_straight_corner_is_degenerate(tmp_path, capsys):
    """Vertex 6 moved to the middle of vertices 1 and 7: face 1 = (1, 6, 7, 2) keeps its area, a
    triangle with a vertex on a side; its corner there is 180 degrees, inside the fold tolerance,
    so it was no fold and the run converged."""
    g = shapes.grid(5, 5, size=(4000.0, 4000.0))
    mesh = _flat_grid_with(6, 0.5 * (g.V[1] + g.V[7]))
    code, out, err, report, _ = _optimize(tmp_path, mesh, capsys)
    assert code == 3 and report["status"] == "degenerate", out + err
    assert report["defects"]["straight_corners"] == {"count": 1, "corners": 1, "faces": [1]}
    assert report["defects"]["folded"]["count"] == 0 and report["defects"]["shrunk_edges"]["count"] == 0
    assert "0 with a shrunk edge, 1 with a straight corner (first [1])" in out


def test_a_clean_mesh_has_no_degenerate_faces(tmp_path, capsys):
    code, out, err, report, _ = _optimize(tmp_path, _saddle(), capsys)
    assert code == 0 and report["status"] == "converged", out + err
    assert report["defects"]["shrunk_edges"] == {"count": 0, "edges": 0, "faces": []}
    assert report["defects"]["straight_corners"] == {"count": 0, "corners": 0, "faces": []}
    assert "degenerate faces: 0 with a shrunk edge, 0 with a straight corner\n" in out
