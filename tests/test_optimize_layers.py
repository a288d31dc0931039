"""Inside ``optimize`` the packages import downwards only (the README's Code layout, bottom to top)."""
from pathlib import Path

from test_layers import _imported

REPO = Path(__file__).resolve().parents[1]
RANK = {
    "errors": 0, "fields": 0, "tolerances": 0, "_lazy": 0, "atomic": 0, "jsontext": 0, "kernels": 0, "warnfilter": 0,
    "_numba_kernels": 0,
    "options": 1, "mesh": 1,
    "linalg": 2, "proximity": 2,
    "terms": 3,
    "result": 4,
    "solvers": 5,
    "api": 6,
    "modelling": 7, "remesh": 7,  # they call the optimizer (the api's, unless the caller passes its own)
}
KNOWN = {}


def _unit(name: str) -> str | None:
    parts = name.split(".")
    return parts[1] if len(parts) > 1 and parts[0] == "optimize" else None


def test_optimize_imports_go_down():
    wrong, seen = [], set()
    for path in sorted((REPO / "optimize").rglob("*.py")):
        rel = path.relative_to(REPO / "optimize")
        src = rel.with_suffix("").parts[0]
        if src == "__init__":
            continue
        assert src in RANK, f"{rel}: a package or module the layer table does not know"
        for name in _imported(path):
            dst = _unit(name)
            if dst is None or dst == src or dst == "__init__":
                continue
            assert dst in RANK, f"{rel} imports {name}: not in the layer table"
            if RANK[dst] > RANK[src]:
                if (src, dst) in KNOWN:
                    seen.add((src, dst))
                else:
                    wrong.append(f"{rel} imports {name} ({src} {RANK[src]} -> {dst} {RANK[dst]})")
    assert not wrong, wrong
    assert seen == set(KNOWN), seen  # a known exception that is gone is taken off the list
