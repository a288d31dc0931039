"""The cadquery extra: a labelled cadquery Assembly of the parts with their exact volumes.

Runs where cadquery is installed (the extra, tested by .ci/run in its own virtual environment);
elsewhere it says why it skips."""
import pytest
from cad_fixtures import dome_parts


cq = pytest.importorskip("cadquery", reason="the optional cadquery extra is not installed in this environment "
                                            "(.ci/run tests it in a virtual environment of its own)")


def test_to_cadquery_names_every_part_with_its_volume():
    from fabricate.export.cadquery_assembly import to_cadquery

    parts = dome_parts(6, 3)
    assy = to_cadquery(parts)
    children = {c.name: c for c in assy.children}
    assert sorted(children) == sorted(p.id for p in parts)
    for p in parts:
        shape = children[p.id].obj
        assert shape.isValid()
        assert shape.Volume() == pytest.approx(p.volume_mm3, rel=1e-9)


def test_cadquery_and_build123d_share_one_opencascade():
    """The extra's point: both import and a build123d solid passes into a cadquery assembly."""
    import build123d as bd

    box = bd.Box(10, 20, 30)
    assy = cq.Assembly().add(cq.Shape.cast(box.wrapped), name="box")
    assert assy.children[0].obj.Volume() == pytest.approx(6000.0)
