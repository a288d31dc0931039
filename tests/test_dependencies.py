"""Every third-party module the code imports is declared in pyproject.toml.

The imports are read from the source (``ast``: every ``import`` and ``from ... import``,
at module level or inside functions) of fabricate/, optimize/, tests/ and benchmarks/;
each top-level name is mapped to the distribution that provides it in this environment.
The package's own modules must come from ``dependencies`` or an optional extra; tests and
benchmarks may also use the ``test`` extra.
"""
import ast
import importlib.metadata as md
import re
import sys
import tomllib
from functools import lru_cache
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
OWN = {"fabricate", "optimize"}
THROUGH = {"OCP": "build123d"}
"""Imported, but declared through the dependency that pins its build: build123d requires the OCP build
it was made with (cadquery-ocp-novtk 8.0 for 0.13, cadquery-ocp 7.8 for 0.10); naming one here would
put two OCP builds into the cadquery extra's environment (see pyproject.toml)."""


def _norm(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _names(requirements) -> set[str]:
    return {_norm(re.match(r"\s*([A-Za-z0-9_.\-]+)", r).group(1)) for r in requirements}


def _declared():
    project = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]
    extras = project.get("optional-dependencies", {})
    return _names(project["dependencies"]), {k: _names(v) for k, v in extras.items()}


def _imports(folder: str) -> dict[str, set[str]]:
    """``{top-level module: {files importing it}}`` of every .py file under ``folder``."""
    # test helpers and benchmark modules imported by name from their own folder
    local = {p.stem for d in ("tests", "benchmarks") for p in (REPO / d).glob("*.py")}
    found: dict[str, set[str]] = {}
    for path in (REPO / folder).rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            for name in names:
                top = name.split(".")[0]
                if top not in sys.stdlib_module_names and top not in OWN and top not in local:
                    found.setdefault(top, set()).add(str(path.relative_to(REPO)))
    return found


@lru_cache(maxsize=1)
def _providers() -> dict:
    return md.packages_distributions()


def _distributions(module: str) -> set[str]:
    return {_norm(d) for d in _providers().get(module, [])}


def test_every_imported_module_is_declared():
    runtime, extras = _declared()
    optional = set().union(*extras.values())
    missing = []
    for folder, allowed in (("fabricate", runtime | optional), ("optimize", runtime | optional),
                            ("tests", runtime | optional), ("benchmarks", runtime | extras["test"])):
        for module, files in sorted(_imports(folder).items()):
            if module in THROUGH:
                assert _norm(THROUGH[module]) in runtime
                provider = _norm(THROUGH[module])
                assert _distributions(module) & _names(md.requires(provider) or []), (module, provider)
                continue
            dists = _distributions(module) or {_norm(module)}  # not installed: its own name
            if not dists & allowed:
                missing.append(f"{module} ({', '.join(sorted(dists))}) imported by {sorted(files)[0]}")
    assert not missing, "imported but not declared in pyproject.toml: " + "; ".join(missing)


def test_the_check_sees_an_undeclared_import(tmp_path, monkeypatch):
    """The parser finds imports inside functions too (a lazy import is still an import)."""
    (tmp_path / "fabricate").mkdir()
    (tmp_path / "fabricate" / "m.py").write_text("def f():\n    import not_a_declared_module.sub\n"
                                                 "from os import path\nimport fabricate.x\n")
    monkeypatch.setattr(sys.modules[__name__], "REPO", tmp_path)
    (tmp_path / "tests").mkdir()
    assert _imports("fabricate") == {"not_a_declared_module": {"fabricate/m.py"}}
