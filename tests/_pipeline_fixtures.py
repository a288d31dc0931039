"""The run shared by the pipeline and report tests: the README quickstart command, once per session.

``finished_run`` runs ``python -m fabricate run configs/quickstart.yaml --out <tmp>`` in a
subprocess (exactly what a user types, see README.md) and yields its exit code, output,
folder and summary for the tests to inspect.
"""
from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


@dataclass
class FinishedRun:
    returncode: int
    stdout: str
    stderr: str
    out: Path
    report: dict

    @property
    def summary(self):
        from types import SimpleNamespace

        return SimpleNamespace(name=self.report["name"], status=self.report["status"])


_RUNS: dict[str, FinishedRun] = {}


@pytest.fixture(scope="session")
def finished_run(tmp_path_factory) -> FinishedRun:
    # imported by two test modules, so pytest sees two fixtures: run the command once per session
    if "quickstart" in _RUNS:
        return _RUNS["quickstart"]
    root = tmp_path_factory.mktemp("quickstart")
    proc = subprocess.run([sys.executable, "-m", "fabricate", "run", "configs/quickstart.yaml", "--out", str(root)],
                          cwd=REPO, capture_output=True, text=True, timeout=600)
    out = root / "quickstart"
    assert proc.returncode in (0, 3), f"quickstart failed ({proc.returncode}):\n{proc.stderr[-3000:]}"
    report = json.loads((out / "report.json").read_text())
    _RUNS["quickstart"] = FinishedRun(proc.returncode, proc.stdout, proc.stderr, out, report)
    return _RUNS["quickstart"]


NO_FILES = {"step": False, "stl": False, "3mf": False, "dxf": False, "svg": False, "bom": False,
            "pictures": False, "html": False, "ifc": False, "3dm": False, "nc1": False, "gltf": False,
            "glass_order": False}


def tiny_config(folder: Path, name: str = "tiny", *, outputs: dict | None = None, **sections):
    """A validated config of a 12-quad noisy dome (``sections`` override whole sections)."""
    from fabricate.app.config import parse_config

    data = {"name": name,
            "input": {"shape": {"name": "dome", "params": {"radius": 5000, "rise": 2000, "meridians": 6,
                                                           "rings": 3, "noise": 0.05, "seed": 3}}},
            "optimize": {"target": "conical", "max_iter": 60},
            "outputs": dict(NO_FILES if outputs is None else outputs)}
    data.update(sections)
    return parse_config(data, source=folder / f"{name}.yaml")
