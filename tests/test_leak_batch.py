"""Batch workers are replaced after JOBS_PER_WORKER jobs (#32), so what a run's native code keeps
cannot add up over a long batch (workers grew 267 -> 415 MB over 50 jobs)."""
from __future__ import annotations

import os

from fabricate.app import batch
from fabricate.app.batch import Job, run_batch


def pid_job(job: Job, out_root: str, force: bool = False) -> int:
    """Stands in for ``run_job`` in a worker: which process ran the job."""
    return os.getpid()


def test_a_worker_runs_at_most_jobs_per_worker_jobs_then_a_fresh_one_takes_over(tmp_path, monkeypatch):
    """Three jobs on one worker, two a worker: the first worker runs two, a fresh process the third
    (each worker a process of its own, never this one)."""
    assert isinstance(batch.JOBS_PER_WORKER, int) and 1 <= batch.JOBS_PER_WORKER <= 50
    monkeypatch.setattr(batch, "JOBS_PER_WORKER", 2)
    monkeypatch.setattr(batch, "run_job", pid_job)
    jobs = [Job(f"j{k}", "j.yaml", config="validated") for k in range(3)]
    pids = run_batch(jobs, tmp_path / "out", workers=1)
    assert pids[0] == pids[1] != pids[2] and os.getpid() not in pids
