"""Memory settings while ``fabricate check`` reads big files: big temporaries reused, no huge pages.

:func:`heap_reuse` is entered by :func:`fabricate.check.check_outputs` and by each child process
of :mod:`fabricate.check_lanes`.
"""
from __future__ import annotations

import ctypes
from contextlib import contextmanager


@contextmanager
def heap_reuse():
    """While the check runs, glibc serves big arrays from its heap and keeps freed memory for the
    next one (``mallopt`` mmap and trim thresholds at 1 GiB), so that the readers' many large
    temporaries do not each fault in fresh pages (on this project's 165 MB STEP file a first read
    spent 40 % of its time in page faults); afterwards the thresholds go back to glibc's defaults
    and the heap is trimmed.  A no-op where there is no glibc.

    numpy's transparent-huge-page advice on its big arrays is turned off meanwhile: served from a
    reused heap they gain nothing from it, and each advised range costs the kernel a 2 MiB page
    to zero and compact (the dome's STEP read: a fifth of its system time)."""
    hugepage = _madvise_hugepage(False)
    try:
        libc = ctypes.CDLL(None)
        mallopt, trim = libc.mallopt, libc.malloc_trim
    except (OSError, AttributeError, TypeError):
        try:
            yield
        finally:
            _madvise_hugepage(hugepage)
        return
    on = mallopt(M_MMAP_THRESHOLD, 1 << 30) and mallopt(M_TRIM_THRESHOLD, 1 << 30)
    try:
        yield
    finally:
        _madvise_hugepage(hugepage)
        if on:
            mallopt(M_MMAP_THRESHOLD, 128 * 1024)
            mallopt(M_TRIM_THRESHOLD, 128 * 1024)
            trim(0)


def _madvise_hugepage(enabled: bool | None) -> bool | None:
    """Set numpy's huge-page advice for new arrays; returns the previous setting (None: this numpy
    has no such switch, and ``enabled=None`` changes nothing)."""
    try:
        from numpy._core.multiarray import _set_madvise_hugepage
    except ImportError:
        return None
    return None if enabled is None else bool(_set_madvise_hugepage(enabled))


M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3   # glibc's mallopt parameters
