"""The layers import downwards only: optimize never imports fabricate; the fabrication stages
(offset, cad, export, structure, report) never import the application layer (fabricate.app)."""
import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
KNOWN: dict[str, str] = {}
"""Upward imports still there, each with the reason; a new one fails the test."""


def _imported(path: Path) -> set[str]:
    """Absolute names of everything ``path`` imports (relative imports resolved)."""
    package = ".".join(path.relative_to(REPO).with_suffix("").parts[:-1])
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = package.split(".")[:len(package.split(".")) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            out.update(f"{module}.{a.name}" for a in node.names)
            out.add(module)
    return out


def test_imports_go_down_the_layers():
    wrong = []
    for path in sorted((REPO / "optimize").rglob("*.py")):
        wrong += [f"{path.relative_to(REPO)} imports {n}" for n in _imported(path) if n.split(".")[0] == "fabricate"]
    for stage in ("offset", "cad", "export", "structure", "report"):
        for path in sorted((REPO / "fabricate" / stage).rglob("*.py")):
            rel = path.relative_to(REPO).as_posix()
            if rel not in KNOWN:
                wrong += [f"{rel} imports {n}" for n in _imported(path) if n.startswith("fabricate.app")]
    assert not wrong, wrong
    for rel in KNOWN:  # a known exception that is gone is taken off the list
        assert any(n.startswith("fabricate.app") for n in _imported(REPO / rel)), rel


def test_relative_imports_are_resolved():
    path = REPO / "fabricate" / "app" / "pipeline.py"
    names = _imported(path)
    assert "fabricate.report.measures.collect_measures" in names and "fabricate.app.stages" in names
