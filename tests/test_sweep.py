"""Exploration at scale and the plot of the classes (#37 items 3, 4): the Pareto front of a sweep, the
sweep's CSV as Design Explorer reads it (in: / out: / img: columns, one row per job), and the classes
picture every run with glass draws, its count the same as report.json's distinct glass shapes."""
from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

from fabricate.app.batch import expand_jobs, parse_sets, run_job
from fabricate.app.sweep import pareto_front, write_sweep

TINY = """name: tiny
input:
  shape: {name: dome, params: {radius: 5000, rise: 2000, meridians: 6, rings: 3, noise: 0.05, seed: 3}}
optimize: {target: conical, max_iter: 60}
outputs: {step: false, stl: false, 3mf: false, dxf: false, svg: false, bom: false, pictures: true, html: false,
          ifc: false, 3dm: false, nc1: false, gltf: false, glass_order: false}
"""


def _dominated_brute(x, y):
    """The definition, pair by pair: dominated when another point is at most as large in both and smaller in one."""
    n = len(x)
    return np.array([any(x[j] <= x[i] and y[j] <= y[i] and (x[j] < x[i] or y[j] < y[i]) for j in range(n))
                     for i in range(n)])


def test_pareto_front_of_known_points():
    # (moved mm, shapes): a staircase of three, one dominated, a duplicate of a front point, a tie in
    # shapes with more movement (dominated), a NaN
    x = [10.0, 20.0, 40.0, 30.0, 20.0, 50.0, np.nan, 5.0]
    y = [90.0, 40.0, 10.0, 50.0, 40.0, 10.0, 1.0, 95.0]
    front = pareto_front(x, y)
    assert front.tolist() == [True, True, True, False, True, False, False, True]
    assert not pareto_front([], []).any()


def test_pareto_front_is_the_definition_on_random_points():
    rng = np.random.default_rng(7)
    x, y = rng.integers(0, 12, 60).astype(float), rng.integers(0, 12, 60).astype(float)  # many ties
    front = pareto_front(x, y)
    assert front.tolist() == (~_dominated_brute(x, y)).tolist()
    assert front.any()


def test_jobs_apart_by_rounding_noise_are_all_on_the_front():
    """The front is taken on the figures as the CSV writes them: a distance apart by 1e-11 mm is the same."""
    from types import SimpleNamespace

    from fabricate.app.sweep import sweep_rows

    jobs = [SimpleNamespace(overrides={"optimize.rationalize": v}, config_file="a.yaml") for v in (None, 20, 50)]
    runs = [SimpleNamespace(status="ok", out_dir=None, facts={"moved_mm": 72.05895651977599 + d, "glass_shapes": 320})
            for d in (0.0, -6e-12, -6e-12)]
    assert [r["out:pareto"] for r in sweep_rows(jobs, runs, ".")] == ["1", "1", "1"]


@pytest.fixture(scope="module")
def tiny_sweep(tmp_path_factory):
    """Two jobs of a 12-panel dome, rationalize off and a 100 mm pull, run one after the other in this
    process (as a batch's worker runs them) and written as a sweep."""
    root = tmp_path_factory.mktemp("sweep")
    cfg = root / "tiny.yaml"
    cfg.write_text(TINY)
    jobs = expand_jobs([cfg], parse_sets(["optimize.rationalize=null,100"]))
    summaries = [run_job(j, str(root / "out")) for j in jobs]
    rows, files = write_sweep(jobs, summaries, root / "out")
    return jobs, summaries, rows, files


def test_sweep_csv_has_design_explorer_columns_and_one_row_per_job(tiny_sweep):
    jobs, summaries, _, files = tiny_sweep
    assert len(jobs) == 2 and all(s.status in ("ok", "tolerance_not_reached") for s in summaries)
    path = files["table"]
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        header, table = reader.fieldnames, list(reader)
    assert all(c.startswith(("in:", "out:", "img:")) for c in header), header
    assert [c for c in header if c.startswith("in:")] == ["in:optimize.rationalize"]
    for col in ("glass shapes", "node types", "beam types", "moved mm", "moved %", "roughness ratio", "status"):
        assert f"out:{col}" in header
    assert len(table) == len(jobs)
    assert [r["in:optimize.rationalize"] for r in table] == ["null", "100"]
    for row, s in zip(table, summaries):
        report = json.loads((Path(s.out_dir) / "report.json").read_text())
        assert int(row["out:glass shapes"]) == report["totals"]["glass_shapes"]
        assert int(row["out:beam types"]) == report["totals"]["beam_types"]
        assert float(row["out:moved mm"]) == pytest.approx(report["measures"]["closeness"]["max_mm"], rel=1e-5)
        assert row["out:status"] == s.status
        image = path.parent / row["img:classes"]
        assert row["img:classes"].endswith("classes.png") and image.is_file()
    on = [r for r in table if r["out:pareto"] == "1"]
    assert on and all(r["out:status"] == "ok" for r in on)
    with files["front"].open(newline="") as fh:
        assert len(list(csv.DictReader(fh))) == len(on)
    assert files["plot"].is_file() and files["plot"].stat().st_size > 1000


def test_classes_picture_counts_the_reports_glass_shapes(tiny_sweep):
    from PIL import Image

    _, summaries, _, _ = tiny_sweep
    for s in summaries:
        folder = Path(s.out_dir)
        report = json.loads((folder / "report.json").read_text())
        with Image.open(folder / "classes.png") as im:
            text = im.text["Description"]
        shapes = int(re.search(r"glass shapes: (\d+)", text).group(1))
        panels = int(re.search(r"panels: (\d+)", text).group(1))
        assert shapes == report["totals"]["glass_shapes"] and panels == report["totals"]["panels"], text
        assert "classes.png" in report["pictures"]
        assert f"{shapes} shapes" in report["pictures"]["classes.png"]
