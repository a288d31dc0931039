"""The compiled kernels' switch from two threads of one process (a batch's jobs on one Dask worker).

``optimize.kernels.disabled()`` (the SQP band factor's NumPy fallback) switches the kernels off for its
own thread only: another thread keeps them (its LDL solve, set up with them, would otherwise find
``get()`` None half-way), and two blocks that end in the other order than they began leave them on.
The interleaving is forced by events, not by timing.
"""
from __future__ import annotations

import threading

import pytest

from optimize import kernels

HANG = 60.0
"""Seconds any one wait may take: only a guard against a hang."""


@pytest.fixture
def compiled(monkeypatch):
    monkeypatch.setattr(kernels, "ENABLED", True)
    if kernels.get() is None:
        pytest.fail("numba is a declared dependency: the compiled kernels must load")


def test_disabled_switches_off_this_thread_only_and_leaves_the_kernels_on(compiled):
    entered, leave, left = threading.Event(), threading.Event(), threading.Event()
    seen: dict[str, object] = {}

    def first() -> None:           # begins first and ends first
        with kernels.disabled():
            seen["first inside"] = kernels.get()
            entered.set()
            leave.wait(HANG)
        left.set()

    t = threading.Thread(target=first)
    t.start()
    try:
        assert entered.wait(HANG)
        seen["other thread"] = kernels.get()                  # while the first thread is inside
        with kernels.disabled():                               # begins after it, ends after it
            seen["second inside"] = kernels.get()
            leave.set()
            assert left.wait(HANG)
            seen["second inside, first gone"] = kernels.get()
    finally:
        leave.set()
        t.join(HANG)
    assert seen["first inside"] is None and seen["second inside"] is None
    assert seen["second inside, first gone"] is None
    assert seen["other thread"] is not None
    assert kernels.get() is not None and kernels.load("fabricate.export._nest_kernel") is not None
