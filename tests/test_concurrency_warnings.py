"""Warning filters of two threads' blocks (optimize.warnfilter): one block at a time, each restoring
what it found, so no filter is left on for the whole process (catch_warnings alone is not
thread-safe: a block that ends after another began restores the other's filter list)."""
from __future__ import annotations

import threading
import warnings

import scipy.sparse.linalg as sla

from optimize.warnfilter import filtered


def test_a_second_threads_block_waits_and_the_filters_end_as_they_were():
    before = list(warnings.filters)
    a_in, a_leave, b_in = threading.Event(), threading.Event(), threading.Event()
    seen = {}

    def a():
        with filtered("error", sla.MatrixRankWarning):
            a_in.set()
            a_leave.wait(60)
            seen["a"] = warnings.filters[0][2] is sla.MatrixRankWarning

    def b():
        with filtered("ignore", DeprecationWarning):
            b_in.set()
            seen["b"] = warnings.filters[0][2] is DeprecationWarning

    ta = threading.Thread(target=a)
    ta.start()
    assert a_in.wait(60)
    tb = threading.Thread(target=b)
    tb.start()
    # b must not get in while a is in (a machine too busy to start b only makes this pass, never fail)
    entered_early = b_in.wait(0.3)
    a_leave.set()
    ta.join(60)
    tb.join(60)
    assert not entered_early
    assert seen == {"a": True, "b": True}
    assert warnings.filters == before  # nothing left on for the process
