"""The README quickstart is what CI runs, and the project reads nothing outside its folder."""
import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def _quickstart_commands() -> list[str]:
    text = (REPO / "README.md").read_text()
    section = text.split("## Quickstart", 1)[1].split("\n## ", 1)[0]
    return [block.strip() for block in re.findall(r"```bash\n(.*?)```", section, flags=re.S)]


def test_quickstart_has_two_complete_commands_and_ci_runs_the_second():
    install_and_run, install_and_test = _quickstart_commands()
    for cmd in (install_and_run, install_and_test):
        assert "\n" not in cmd and cmd.startswith("python3 -m venv .venv && .venv/bin/pip install ")
    assert install_and_run.endswith(".venv/bin/fabricate run configs/quickstart.yaml")
    assert install_and_test.endswith(".venv/bin/python -m pytest -q")
    ci = (REPO / ".ci" / "run").read_text().strip().splitlines()
    assert ci[-1] == install_and_test
    assert (REPO / "configs" / "quickstart.yaml").is_file()


def test_nothing_in_the_project_reads_beside_the_repository():
    outside = ("../" + "shared", "shared" + "/data")  # spelled apart so this file does not match itself
    hits = []
    for folder in ("optimize", "fabricate", "configs", "tests", "benchmarks", ".ci"):
        for path in (REPO / folder).rglob("*"):
            if path.is_file() and path.suffix in (".py", ".yaml", ".yml", ".toml", "", ".sh"):
                text = path.read_text(errors="replace")
                hits += [f"{path.relative_to(REPO)}: {s}" for s in outside if s in text]
    assert not hits, hits


def test_the_readme_layout_shows_every_optimize_package():
    text = (REPO / "README.md").read_text()
    layout = text[text.index("## Layout"):]
    layout = layout[:layout.index("\n## ", 1)]
    packages = sorted(p.parent.name for p in (REPO / "optimize").glob("*/__init__.py"))
    assert packages and all(re.search(rf"^  {name}/ ", layout, re.M) for name in packages), packages
    for name in re.findall(r"^  (\w+)/ ", layout[layout.index("optimize/"):layout.index("fabricate/")], re.M):
        assert (REPO / "optimize" / name / "__init__.py").is_file(), name  # and no line for a package gone
