"""Warning filters for a block of code that stay right when threads use them at once.

``warnings.catch_warnings`` saves and restores the process-wide filter list: two threads in such
blocks at once (the jobs of a dask batch worker) can restore each other's filters and leave one on
for the whole process (an "error" filter for ``MatrixRankWarning`` turned a later warning into an
exception).  :func:`filtered` runs such blocks one at a time, so each restores what it found.
"""
from __future__ import annotations

import contextlib
import threading
import warnings
from typing import Iterator

_LOCK = threading.RLock()


@contextlib.contextmanager
def filtered(action: str, category: type[Warning]) -> Iterator[None]:
    """``warnings.simplefilter(action, category)`` for the block, one block at a time in the process."""
    with _LOCK, warnings.catch_warnings():
        warnings.simplefilter(action, category)
        yield
