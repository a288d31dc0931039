"""The layout plan's ids (DXF and picture): scaled to their part, apart, on a leader where crowded."""
import functools
from pathlib import Path

import numpy as np
import pytest

from fabricate.export.plan_labels import PAD, boxes_overlap, dxf_measure, label_counts, place_labels

REPO = Path(__file__).resolve().parents[1]


@functools.cache
def quickstart_parts():
    """The parts of configs/quickstart.yaml, built in process (input, optimize, offset, CAD: about 1 s)."""
    from fabricate.app import stages
    from fabricate.app.config import load_config

    cfg = load_config(REPO / "configs" / "quickstart.yaml")
    inp = stages.stage_input(cfg)
    opt = stages.stage_optimize(cfg, inp)
    off = stages.stage_offset(cfg, opt)
    return stages.stage_cad(cfg, opt, off).parts


def test_quickstart_layout_plan_dxf_ids_are_readable_and_apart(tmp_path):
    import ezdxf

    from fabricate.export import write_layout_plan

    parts = quickstart_parts()
    facts = write_layout_plan(parts, tmp_path / "plan.dxf")
    doc = ezdxf.readfile(str(tmp_path / "plan.dxf"))
    assert not doc.audit().has_errors
    msp = doc.modelspace()
    texts = list(msp.query("TEXT[layer=='IDS']"))
    ids = {p.id.split(".")[0] for p in parts.panels} | {p.id.split(".")[0] for p in parts.beams}
    assert sorted(t.dxf.text for t in texts) == sorted(ids)             # every id once, none left out
    scale = int(facts["plot_scale"].split(":")[1])
    assert scale == 20 and facts["labels"]["skipped"] == 0
    boxes = []
    for t in texts:  # the box of each TEXT as written (centre, height, the characters)
        c = np.array(t.dxf.align_point)[:2]
        w, h = dxf_measure(t.dxf.text)
        s = t.dxf.height
        assert s >= 2.5 * scale - 1e-9                                 # at least 2.5 mm on paper
        boxes.append((c[0] - 0.5 * w * s, c[1] - 0.5 * h * s, c[0] + 0.5 * w * s, c[1] + 0.5 * h * s))
    assert boxes_overlap(boxes) == []
    heights = {t.dxf.text: t.dxf.height for t in texts}
    assert min(heights[p] for p in ids if p[0] == "P") > max(heights[b] for b in ids if b[0] == "B")
    assert len(msp.query("LINE[layer=='LEADERS']")) == facts["labels"]["leader"]
    assert "1:20" in next(iter(msp.query("MTEXT[layer=='TITLE']"))).text


def test_quickstart_layout_plan_picture_ids_are_apart_at_their_drawn_ink():
    """The picture's ids as drawn (glyph outlines of every label, their bounding boxes): none overlaps,
    none is left out, none is smaller than PLAN_MIN_PT."""
    from fabricate.report.pictures import _glyph_run
    from fabricate.report.shop_pictures import PLAN_MIN_PT, plan_drawing, plan_layout

    lay = plan_layout(plan_drawing(quickstart_parts()))
    labels = lay["labels"]
    assert label_counts(labels)["skipped"] == 0 and len(labels) == 36 + 84
    pt = 72.0 * lay["inch_per_mm"]
    ink = []
    for lab in labels:
        V = _glyph_run(lab["text"])[0] * lab["size"] + lab["centre"]
        ink.append((*V.min(axis=0), *V.max(axis=0)))
        assert lab["size"] * pt >= PLAN_MIN_PT - 1e-9
    assert boxes_overlap(ink) == []


def test_crowded_short_beams_get_leaders_and_never_overlap():
    """Twelve 40 mm beams around one node with 30 mm text: at their midpoints the ids would pile up;
    placed, they sit apart, the ones with no room beside their beam on a leader from it."""
    phi = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    u = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    items = [{"text": f"B{i + 1:04d}", "kind": "beam", "segment": np.stack([5 * u[i], 45 * u[i]]),
              "anchor": 25 * u[i]} for i in range(12)]
    naive = [(*(it["anchor"] - (75, 15)), *(it["anchor"] + (75, 15))) for it in items]
    assert len(boxes_overlap(naive)) > 12                              # the problem: they overlap
    labels = place_labels(items, dxf_measure, 30.0, 90.0)
    counts = label_counts(labels)
    assert counts["skipped"] == 0 and counts["leader"] > 0
    grown = [(b[0] - PAD * lab["size"], b[1] - PAD * lab["size"], b[2] + PAD * lab["size"], b[3] + PAD * lab["size"])
             for lab in labels for b in [lab["box"]]]
    assert boxes_overlap(grown) == []
    for it, lab in zip(items, labels):
        assert lab["size"] == pytest.approx(30.0)
        if lab["how"] == "leader":  # from its beam's middle to the edge of its box
            np.testing.assert_allclose(lab["leader"][0], it["anchor"])
            x0, y0, x1, y1 = lab["box"]
            e = lab["leader"][1]
            assert x0 - 1e-9 <= e[0] <= x1 + 1e-9 and y0 - 1e-9 <= e[1] <= y1 + 1e-9


def test_a_panel_id_shrinks_to_fit_its_panel_or_leaves_it_on_a_leader():
    big = np.array([[0, 0], [2000, 0], [2000, 1000], [0, 1000]], float)
    small = np.array([[3000, 0], [3100, 0], [3100, 60], [3000, 60]], float)
    items = [{"text": "P0001", "kind": "panel", "polygon": big, "anchor": big.mean(axis=0)},
             {"text": "P0002", "kind": "panel", "polygon": small, "anchor": small.mean(axis=0)}]
    a, b = place_labels(items, dxf_measure, 50.0, 150.0)
    assert a["how"] == "inside" and a["size"] == pytest.approx(150.0)   # capped at the largest size
    assert b["how"] == "leader" and b["size"] == pytest.approx(50.0)    # 5 x 50 mm does not fit in 100 x 60
    x0, y0, x1, y1 = a["box"]
    assert x0 > 0 and x1 < 2000 and y0 > 0 and y1 < 1000
