"""Batches: sweeps, job names, one broken config among good ones, CSV, and a Dask cluster."""
from __future__ import annotations

import csv
import re
import subprocess
import sys
from pathlib import Path

import pytest

from fabricate.app.batch import (Job, expand_jobs, exit_code, make_executor, parse_sets, run_batch, split_values,
                            write_csv)
from fabricate.app.pipeline import RunSummary
from optimize.errors import ConfigError

REPO = Path(__file__).resolve().parents[1]

SMALL = """\
name: {name}
input:
  shape: {{name: dome, params: {params}}}
optimize: {{max_iter: 60}}
outputs: {{step: false, stl: false, 3mf: false, dxf: false, svg: false, html: false, pictures: false}}
"""


def small_config(folder: Path, name: str, params: str = "{}") -> Path:
    path = folder / f"{name}.yaml"
    path.write_text(SMALL.format(name=name, params=params))
    return path


def test_split_values_keeps_lists_and_quotes():
    assert split_values("8,10,12") == ["8", "10", "12"]
    assert split_values("[0, -200],[0, -300]") == ["[0, -200]", "[0, -300]"]
    assert split_values("'a,b',c") == ["'a,b'", "c"]


def test_parse_sets_reads_yaml_values_and_refuses_nonsense():
    sets = parse_sets(["parts.glass_thickness=8,10,12", "offset.distances=[0, -150]", "outputs.step=false"])
    assert sets == {"parts.glass_thickness": [8, 10, 12], "offset.distances": [[0, -150]],
                    "outputs.step": [False]}
    for bad in ("parts.glass_thickness", "=3", "a.b="):
        with pytest.raises(ConfigError, match="KEY=VALUE"):
            parse_sets([bad])
    with pytest.raises(ConfigError, match="given twice"):
        parse_sets(["a.b=1", "a.b=2"])


def test_sweep_is_the_product_with_unique_folder_names(tmp_path):
    cfg = small_config(tmp_path, "d")
    jobs = expand_jobs([cfg], parse_sets(["parts.glass_thickness=8,10", "parts.beam_width=60,80",
                                          "optimize.max_iter=30"]))
    assert len(jobs) == 4
    names = [j.name for j in jobs]
    assert len(set(names)) == 4
    assert "d__glass_thickness=8__beam_width=60" in names  # only swept keys name the folder
    assert {(j.config.parts.glass_thickness, j.config.parts.beam_width) for j in jobs} == \
        {(8, 60), (8, 80), (10, 60), (10, 80)}
    assert all(j.config.optimize.max_iter == 30 for j in jobs)


def test_bad_sweep_value_becomes_a_failed_job_not_an_exception(tmp_path):
    cfg = small_config(tmp_path, "d")
    jobs = expand_jobs([cfg], parse_sets(["parts.glass_thickness=8,-1"]))
    assert [j.config is None for j in jobs] == [False, True]
    assert "parts.glass_thickness" in jobs[1].error and "from --set" in jobs[1].error


def test_two_configs_with_one_name_are_refused(tmp_path):
    a = small_config(tmp_path, "same")
    b = tmp_path / "other.yaml"
    b.write_text(a.read_text())
    with pytest.raises(ConfigError, match="two jobs would write outputs/same/"):
        expand_jobs([a, b])


def test_csv_and_exit_code(tmp_path):
    rows = [RunSummary("a", "ok", 0, faces=12, planarity=1e-9, conical=2e-8, parts=30, seconds=1.5),
            RunSummary("b", "bad_input", 2, message="x.yaml:3: units: value 'km' ...")]
    path = write_csv(rows, tmp_path / "s.csv")
    table = list(csv.DictReader(path.open()))
    assert [r["name"] for r in table] == ["a", "b"]
    assert table[0]["planarity"] == "1e-09" and table[1]["faces"] == "" and "units" in table[1]["message"]
    assert exit_code(rows) == 2 and exit_code(rows[:1]) == 0


def test_batch_of_three_with_one_broken(tmp_path):
    """Two good configs and one broken: two folders, one reported failure, the CLI says so."""
    good = [small_config(tmp_path, "one"), small_config(tmp_path, "two", "{rings: 3}")]
    broken = tmp_path / "broken.yaml"
    broken.write_text("input: {mesh: no_such_file.obj}\n")
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "fabricate", "batch", *map(str, good), str(broken),
                           "--workers", "2", "--out", str(out)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 2, proc.stderr
    table = {r["name"]: r for r in csv.DictReader((out / "batch_summary.csv").open())}
    assert set(table) == {"one", "two", "broken"}
    assert table["broken"]["status"] == "bad_input" and "no_such_file.obj" in table["broken"]["message"]
    for name in ("one", "two"):
        assert table[name]["status"] in ("ok", "tolerance_not_reached"), table[name]
        assert (out / name / "report.json").is_file() and (out / name / "mesh.obj").is_file()
        assert int(table[name]["faces"]) > 0
    assert not (out / "broken").exists()
    assert "broken" in proc.stdout and re.search(r"batch: [12] of 3 ok", proc.stdout), proc.stdout


def test_worker_exception_is_one_row(tmp_path, monkeypatch):
    """A job whose pipeline raises an unexpected error is reported; the others still run."""
    import fabricate.app.batch as batch

    cfg = small_config(tmp_path, "fine")
    jobs = expand_jobs([cfg]) + [Job("ghost", "ghost.yaml", error="ghost.yaml: input: required key is missing")]

    def boom(config, out_root, **kwargs):
        raise RuntimeError("injected")

    monkeypatch.setattr(batch, "run_pipeline", boom)
    summary = batch.run_job(jobs[0], str(tmp_path))
    assert summary.status == "error" and "RuntimeError: injected" in summary.message
    assert batch.run_job(jobs[1], str(tmp_path)).status == "bad_input"


def test_batch_on_a_local_dask_cluster(tmp_path):
    distributed = pytest.importorskip("distributed", reason="dask[distributed] is not installed "
                                                            "(pip install '.[test]')")
    cfgs = [small_config(tmp_path, "d1"), small_config(tmp_path, "d2", "{rings: 3}")]
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        summaries = run_batch(expand_jobs(cfgs), tmp_path / "out", scheduler=cluster.scheduler_address)
    assert [s.name for s in summaries] == ["d1", "d2"]
    for s in summaries:
        assert s.status in ("ok", "tolerance_not_reached"), s.message
        assert (tmp_path / "out" / s.name / "report.json").is_file()


def test_unreachable_scheduler_is_bad_input():
    pytest.importorskip("distributed", reason="dask[distributed] is not installed")
    with pytest.raises(ConfigError, match="cannot connect to the Dask scheduler"):
        make_executor(1, "tcp://127.0.0.1:9", timeout=1.0)


def test_a_killed_worker_costs_one_retry_not_the_batch(tmp_path):
    """Three jobs on two workers: a healthy one, one whose worker dies the first time
    (``os._exit`` as it receives the job), one whose worker dies every time.  The pool breaks;
    every job it held runs again on its own: two finish ok, the third is reported lost, the
    batch exits 1 (a lost job comes before any other outcome) and no temporary folder is left."""
    from _runsafe_jobs import dying

    jobs = expand_jobs([small_config(tmp_path, n, "{rings: 3}") for n in ("healthy", "once", "always")])
    jobs[1] = dying(jobs[1], str(tmp_path / "died-once"))
    jobs[2] = dying(jobs[2])
    seen = []
    summaries = run_batch(jobs, tmp_path / "out", workers=2, on_done=lambda s: seen.append(s.name))
    by = {s.name: s for s in summaries}
    assert [s.name for s in summaries] == ["healthy", "once", "always"] and sorted(seen) == sorted(by)
    assert by["healthy"].status in ("ok", "tolerance_not_reached"), by["healthy"].message
    assert by["once"].status in ("ok", "tolerance_not_reached"), by["once"].message
    assert any("second attempt" in n for n in by["once"].notes)
    assert (by["always"].status, by["always"].exit_code) == ("lost", 1)
    assert "died twice" in by["always"].message and "BrokenProcessPool" in by["always"].message
    assert exit_code(summaries) == 1
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["healthy", "once"]


def test_a_batch_of_too_many_jobs_is_refused_before_a_config_is_read(tmp_path, monkeypatch):
    from fabricate.app import batch

    calls = []
    monkeypatch.setattr(batch, "load_config", lambda *a, **k: calls.append(a))
    sets = parse_sets([f"parts.glass_thickness={','.join(map(str, range(1, 41)))}",
                       f"parts.beam_width={','.join(map(str, range(10, 51)))}",
                       "offset.distances=[0,-200],[0,-201],[0,-202]", "parts.beam_depth=200",
                       f"parts.node.cap_mm={','.join(map(str, range(5, 12)))}"])
    with pytest.raises(ConfigError, match=r"batch of 34,440 jobs \(1 config x 40 parts.glass_thickness x 41 "
                                          r"parts.beam_width x 3 offset.distances x 7 parts.node.cap_mm\); "
                                          r"expected at most 10,000") as info:
        expand_jobs([tmp_path / "a.yaml"], sets)
    assert info.value.exit_code == 2 and calls == []
