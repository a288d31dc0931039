"""JSON read back from files that a user, another program or an attacker may have changed since they were
written (run markers, owner records, ``report.json``, ``flat.json``, GLB documents).

:func:`loads` is :func:`json.loads` whose every failure on bad text is a ``ValueError``: the standard
reader raises ``RecursionError`` for arrays or objects nested deeper than Python's recursion limit
(``[[[[...`` a hundred thousand times: a few hundred bytes), which callers that expect ``ValueError``
for a bad file would let through as an internal error.
"""
from __future__ import annotations

import json


def loads(text):
    """``json.loads(text)``; ``ValueError`` for any text that is not JSON it can read."""
    try:
        return json.loads(text)
    except RecursionError:
        raise ValueError("JSON nested deeper than the reader follows; expected a JSON document of "
                         "a few levels") from None
