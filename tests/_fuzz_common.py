"""What the fuzz tests of the mesh readers share: the hypothesis budget, the tally and the case type.

``FUZZ_EXAMPLES`` (default 40) sets the number of examples per property; the search is
derandomized so CI runs the same cases every time.
"""
from __future__ import annotations

import os
from collections import Counter

from hypothesis import HealthCheck, settings

EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "40"))
FUZZ = settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
                suppress_health_check=list(HealthCheck), print_blob=True)
TALLY: Counter = Counter()  # (input class, outcome) -> count, printed by a campaign


class Case(tuple):
    """(labels, extension, bytes) with a short repr (hypothesis prints failing cases)."""

    def __repr__(self):
        labels, ext, data = self
        return f"Case({labels}, {ext!r}, {len(data)} bytes: {data[:160]!r}...)"


def print_tally(clean: tuple[str, ...]) -> None:
    """The campaign's table: per input class, how many were tried, how many ended clean, each outcome."""
    classes = sorted({c for c, _ in TALLY})
    outcomes = sorted({o for _, o in TALLY})
    print(f"\n{'input class':40s} {'tried':>6s} {'clean':>6s} " + " ".join(f"{o:>11s}" for o in outcomes))
    for c in classes:
        tried = sum(TALLY[c, o] for o in outcomes)
        ok = sum(TALLY[c, o] for o in clean)
        print(f"{c:40s} {tried:6d} {ok:6d} " + " ".join(f"{TALLY[c, o]:11d}" for o in outcomes))
