"""Issue 30 item 6, for OBJ: the unit an exporter writes in the header comment (Maya: ``# This file
uses centimeters as units ...``) is used when the config gives none; a mesh read in mm (no unit
given or stated) that is smaller or larger than any roof gets one sentence, first in the run's
paragraph, naming its size and the unit that would make sense of it."""
from __future__ import annotations

import json

from fabricate.app.config import load_config
from fabricate.app.pipeline import run_pipeline
from optimize.mesh.io import write_mesh
from optimize.mesh.io.api import mesh_units
from optimize.modelling import shapes

LIGHT = {f"outputs.{k}": False for k in ("step", "stl", "3mf", "dxf", "svg", "ifc", "3dm", "nc1", "gltf",
                                           "pictures", "html", "glass_order")}


def _roof_obj(path, header: str = "", scale: float = 1.0):
    """A 12 x 12 (units) conical dome as OBJ, ``header`` lines first."""
    mesh = shapes.revolution(shapes.dome_profile(radius=6.0, rise=2.0, k=4), 8, name="dome")
    write_mesh(path, mesh.with_vertices(mesh.V * scale))
    text = path.read_text()
    path.write_text(header + text)
    return path


def test_a_maya_header_states_the_unit_and_only_the_header_is_read(tmp_path):
    maya = "# This file uses centimeters as units for non-parametric coordinates.\n\nmtllib x.mtl\n"
    assert mesh_units(_roof_obj(tmp_path / "a.obj", maya)) == ("centimeters", 10.0)
    assert mesh_units(_roof_obj(tmp_path / "b.obj", "# exported by a tool\n")) is None
    late = _roof_obj(tmp_path / "c.obj")
    late.write_text(late.read_text() + "# This file uses meters as units\n")  # after the records: not a header
    assert mesh_units(late) is None


def _config(tmp_path, obj, **more):
    text = f"name: roof\ninput: {{mesh: {json.dumps(str(obj))}}}\n" + "".join(f"{k}: {v}\n" for k, v in more.items())
    (tmp_path / "roof.yaml").write_text(text)
    return load_config(tmp_path / "roof.yaml", overrides=LIGHT)


def test_a_maya_obj_in_centimetres_is_read_in_centimetres(tmp_path):
    obj = _roof_obj(tmp_path / "roof.obj", "# This file uses centimeters as units for non-parametric coordinates.\n",
                    scale=100.0)  # 12 m across, in cm
    cfg = _config(tmp_path, obj)
    assert cfg.units == "cm" and "centimeters" in cfg.units_note
    assert cfg.mm_per_unit == 10.0
    assert _config(tmp_path, obj, units="m").units == "m"  # the config's unit wins (and is warned about)


def test_a_roof_read_in_mm_that_is_millimetres_across_is_named_with_the_unit_that_fits(tmp_path):
    obj = _roof_obj(tmp_path / "roof.obj")  # 12 units across: a roof in metres
    summary = run_pipeline(_config(tmp_path, obj), tmp_path / "out")
    assert summary.decision.startswith("Units not given: the mesh was read in mm, ")
    first = summary.decision.split(". ")[0]
    assert "set units: m (" in first and " m across)" in first
    diag = json.loads((tmp_path / "out" / "roof" / "report.json").read_text())["result_mesh"]["bbox_diagonal_mm"]
    assert 1.0 < diag < 1000.0 and f"{diag:.4g} mm across its bounding box" in first
    # said once, and not when the unit is given, even as mm
    assert summary.decision.count("Units not given") == 1
    again = run_pipeline(_config(tmp_path, obj, units="mm"), tmp_path / "out2")
    assert "Units not given" not in again.decision
