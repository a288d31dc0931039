"""Requirements fail the run; information is a warning in the headline with its value in mm."""
import numpy as np

from fabricate.offset import offset_structure
from fabricate.app.pipeline import outcome
from fabricate.app.requirements import apply_requirements, default_requirements, warnings
from optimize.modelling import shapes


def _twisted():
    a = np.stack([np.linspace(0, 6000, 5), np.zeros(5), 2000 * np.sin(np.linspace(0, 2, 5))], axis=1)
    b = np.stack([np.zeros(4), np.linspace(0, 4500, 4), 2000 * np.cos(np.linspace(0, 2, 4))], axis=1)
    return offset_structure(shapes.translational(a, b), (0.0, -200.0))


def _measures():
    return {"planarity": {"max": 1e-9, "tolerance": 1e-6, "pass": True, "unit": "relative"},
            "circular": {"max": 0.2, "tolerance": 1e-6, "pass": False, "unit": "rad", "max_deg": 11.5},
            "closeness": {"max": 0.01, "tolerance": 5e-3, "pass": False, "unit": "relative", "max_mm": 72.0}}


def test_shop_defaults_make_the_target_and_the_beam_twist_requirements():
    assert set(default_requirements("conical")) == {"planarity", "folded", "beam_twist", "conical", "beam_planarity"}
    assert "circular" not in default_requirements("conical") and "circular" in default_requirements("circular")


def test_a_millimetre_of_beam_twist_fails_the_run_by_default():
    s = _twisted()
    m = apply_requirements(_measures(), s, None, "pq", 1.0)
    assert m["beam_twist"]["max"] == np.abs(s.beam_twist_mm).max() > 1.0 and m["beam_twist"]["enforced"]
    out = outcome(m)
    assert out.exit_code == 3 and "beam_twist" in out.failed
    assert m["circular"]["role"] == "reported" and m["closeness"]["role"] == "information"


def test_information_beyond_its_tolerance_is_a_warning_with_its_value_in_mm():
    m = apply_requirements(_measures(), _twisted(), ["planarity"], "pq", 1.0)
    out = outcome(m)
    assert out.exit_code == 0 and out.status == "ok"
    lines = warnings(m)
    assert any(w.startswith("closeness 72 mm") for w in lines)
    assert not any(w.startswith("circular") for w in lines)  # a pq run did not ask for circles
    assert any(w.startswith("beam_twist ") and " mm " in w for w in lines)
    assert "warning(s)" in out.message and "every requirement met" in out.message


def test_the_headline_has_no_red_fail_under_a_green_banner():
    from fabricate.report.html import _passfail

    m = apply_requirements(_measures(), None, ["planarity"], "conical", 1.0)
    assert "FAIL" not in _passfail(m["closeness"]) and "warning" in _passfail(m["closeness"])
    m = apply_requirements(_measures(), None, ["closeness"], "conical", 1.0)
    assert "FAIL" in _passfail(m["closeness"])


def test_the_defect_of_a_target_not_asked_for_is_reported_not_warned():
    m = apply_requirements(_measures(), None, None, "conical", 1.0)
    assert m["circular"]["role"] == "reported" and not any(w.startswith("circular") for w in warnings(m))
    limits = {"corner": {"limit": ">= 30 deg", "count": 2, "ids": ["P0008", "P0030"]}}
    assert any("P0008, P0030" in w and "corner" in w for w in warnings(m, limits))
