"""Batch jobs that kill the worker process that unpickles them (for tests of lost workers)."""
from __future__ import annotations

import os
from pathlib import Path

from fabricate.app.batch import Job


class DyingJob(Job):
    """A job whose worker process dies (``os._exit``) when it receives it, in any process but
    the one that made it; with ``flag`` only the first time (the flag file records it)."""

    def arm(self, flag: str | None = None) -> "DyingJob":
        self._parent, self._flag = os.getpid(), flag
        return self

    def __setstate__(self, state):
        self.__dict__.update(state)
        if os.getpid() == state.get("_parent"):
            return
        flag = state.get("_flag")
        if flag is None:
            os._exit(9)
        if not Path(flag).exists():
            Path(flag).touch()
            os._exit(9)


def dying(job: Job, flag: str | None = None) -> DyingJob:
    return DyingJob(**{k: getattr(job, k) for k in ("name", "config_file", "overrides", "config", "error")}).arm(flag)
