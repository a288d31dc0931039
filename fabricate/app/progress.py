"""Progress reporting of a run: one bar per pipeline stage.

The pipeline talks to a small protocol (``start``, ``advance``, ``done``);
:class:`NullProgress` ignores it (batch workers, tests), :class:`RichProgress`
draws one rich progress row per stage on stderr.
"""
from __future__ import annotations

import time


class NullProgress:
    """Receives stage events and does nothing."""

    def start(self, stage: str, total: int | None = None, note: str = "") -> None:
        """A stage begins; ``total`` steps if known."""

    def advance(self, stage: str, steps: int = 1, note: str = "") -> None:
        """``steps`` more steps of ``stage`` are done; ``note`` says where it is."""

    def done(self, stage: str, note: str = "") -> None:
        """A stage finished (``note``: a one-line result)."""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        return None


class RecordingProgress(NullProgress):
    """Keeps every event as ``(event, stage, note)`` (for tests and logs)."""

    def __init__(self) -> None:
        self.events: list[tuple[str, str, str]] = []

    def start(self, stage, total=None, note=""):
        self.events.append(("start", stage, note))

    def advance(self, stage, steps=1, note=""):
        self.events.append(("advance", stage, note))

    def done(self, stage, note=""):
        self.events.append(("done", stage, note))


class RichProgress(NullProgress):
    """One rich progress bar per stage; use as a context manager.

    stages : the stage names in order (rows appear as stages start).
    """

    def __init__(self, stages: tuple[str, ...], title: str = "", console=None) -> None:
        from rich.console import Console
        from rich.progress import (BarColumn, MofNCompleteColumn, Progress, SpinnerColumn, TextColumn,
                                   TimeElapsedColumn)

        self._stages = stages
        self._title = title
        self._progress = Progress(
            SpinnerColumn(finished_text="[green]done"), TextColumn("{task.description:<10}"),
            BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(), TextColumn("{task.fields[note]}"),
            console=console or Console(stderr=True), transient=False)
        self._tasks: dict[str, int] = {}
        self._t0: dict[str, float] = {}

    def __enter__(self):
        self._progress.__enter__()
        if self._title:
            self._progress.console.print(self._title)
        return self

    def __exit__(self, *exc) -> None:
        self._progress.__exit__(*exc)

    def start(self, stage, total=None, note=""):
        self._t0[stage] = time.perf_counter()
        self._tasks[stage] = self._progress.add_task(stage, total=total, note=note)

    def advance(self, stage, steps=1, note=""):
        task = self._tasks.get(stage)
        if task is not None:
            self._progress.update(task, advance=steps, note=note)

    def done(self, stage, note=""):
        task = self._tasks.get(stage)
        if task is None:
            return
        t = self._progress.tasks[[x.id for x in self._progress.tasks].index(task)]
        total = t.total if t.total is not None else max(t.completed, 1)
        self._progress.update(task, total=total, completed=total, note=note)
