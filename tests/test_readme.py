"""The README quickstart is what CI runs, the README stays short and its links and the docs pages' resolve,
and the project reads nothing outside its folder."""
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


def test_the_layout_page_shows_every_optimize_package():
    text = (REPO / "docs" / "layout.md").read_text()
    layout = text[text.index("## Packages"):]
    layout = layout[:layout.index("\n## ", 1)]
    packages = sorted(p.parent.name for p in (REPO / "optimize").glob("*/__init__.py"))
    assert packages and all(re.search(rf"^  {name}/ ", layout, re.M) for name in packages), packages
    for name in re.findall(r"^  (\w+)/ ", layout[layout.index("optimize/"):layout.index("fabricate/")], re.M):
        assert (REPO / "optimize" / name / "__init__.py").is_file(), name  # and no line for a package gone


def _prose(text: str) -> str:
    """The text outside fenced code blocks, with inline code spans kept as a word."""
    text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)
    return re.sub(r"`[^`\n]*`", "code", text)


def _anchors(text: str) -> set[str]:
    """GitHub's heading anchors: lower case, punctuation dropped, spaces as hyphens, repeats numbered."""
    seen: dict[str, int] = {}
    for heading in re.findall(r"^#{1,6} +(.+?) *$", re.sub(r"^```.*?^```", "", text, flags=re.S | re.M), re.M):
        slug = re.sub(r"[^\w\- ]", "", heading.lower()).replace(" ", "-")
        seen[slug] = seen.get(slug, -1) + 1
        if seen[slug]:
            seen[f"{slug}-{seen[slug]}"] = 0
    return set(seen)


def _pages() -> list[Path]:
    return [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]


def test_the_readme_is_short_and_every_relative_link_resolves():
    readme_lines = (REPO / "README.md").read_text().count("\n")
    broken = []
    for page in _pages():
        for target in re.findall(r"\]\(([^)\s]+)\)", _prose(page.read_text())):
            if re.match(r"[a-z]+:", target):
                continue  # https:, mailto: ...
            path, _, anchor = target.partition("#")
            dest = (page.parent / path).resolve() if path else page
            if not dest.is_file():
                broken.append(f"{page.relative_to(REPO)}: {target} (no such file)")
            elif anchor and dest.suffix == ".md" and anchor not in _anchors(dest.read_text()):
                broken.append(f"{page.relative_to(REPO)}: {target} (no such heading)")
    assert not broken, broken
    assert readme_lines <= 260, f"README.md has {readme_lines} lines; move detail into docs/"


def test_every_docs_page_is_linked_from_where_to_read_on():
    text = (REPO / "README.md").read_text()
    assert "\n## Where to read on\n" in text, "README.md has no section 'Where to read on'"
    section = text.split("\n## Where to read on\n", 1)[1].split("\n## ", 1)[0]
    pages = sorted(p.name for p in (REPO / "docs").glob("*.md"))
    missing = [p for p in pages if f"](docs/{p})" not in section]
    assert pages and not missing, missing
