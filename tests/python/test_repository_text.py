"""What the repository's text may say: generated pages carry no path of the machine that
made them, tests and templates name no issue or defect by number, and every file a comment
cites is in the repository."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# The pages a program writes (their generator, their template), and the evaluation's tables.
GENERATED_PAGES = ("docs/benchmarks.md", "docs/evaluation/README.md")
# An absolute path on the machine that ran a generator: a home, a temporary folder, an
# installed package's folder, a work tree.
MACHINE_PATH = re.compile(
    r"(?<![\w.~])/(?:root|home|tmp|usr|opt|var|work|srv|mnt)/\S*|site-packages|dist-packages"
)
# The word issue or defect, then a number (after a space, a hyphen or a hash), any case.
NUMBERED = re.compile(r"\b(?:issue|defect)s?[ -]?#?\d+", re.IGNORECASE)


def tracked(*patterns: str) -> list[Path]:
    result = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard", "--", *patterns],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    if result.returncode != 0:
        pytest.skip("not a git checkout")
    return [ROOT / line for line in result.stdout.splitlines() if (ROOT / line).is_file()]


@pytest.mark.parametrize(
    "page",
    [*GENERATED_PAGES, *sorted(p.relative_to(ROOT).as_posix() for p in tracked("docs/**.csv"))],
)
def test_a_generated_page_carries_no_machine_path(page):
    text = (ROOT / page).read_text()
    found = [m.group(0) for m in MACHINE_PATH.finditer(text)]
    assert found == [], f"{page} names the generating machine's paths: {found}"


def test_tests_and_templates_name_no_issue_or_defect_by_number():
    files = tracked("tests/**", "tools/**/page.md", "tools/benchmarks/page.md")
    files = [f for f in files if f.suffix in (".py", ".cpp", ".h", ".sh", ".md", ".json", ".txt")]
    assert len(files) > 50
    found = [
        f"{f.relative_to(ROOT)}:{n}: {line.strip()}"
        for f in files
        for n, line in enumerate(f.read_text(errors="replace").splitlines(), 1)
        if NUMBERED.search(line)
    ]
    assert found == [], "numbers of issues or defects:\n" + "\n".join(found)


def cited_files(text: str) -> set[str]:
    """The Markdown files a text names (absolute examples such as /tmp/x.md left out)."""
    return {m for m in re.findall(r"(?<![\w/.])[\w./-]*\w\.md\b", text) if not m.startswith("/")}


def test_every_file_a_comment_cites_is_in_the_repository():
    sources = tracked("core/**", "server/**", "addon/**", "tools/**", "tests/**", "examples/**")
    sources += tracked("cmake/**", "CMakeLists.txt", "pyproject.toml")
    sources = [f for f in sources if f.suffix in (".py", ".cpp", ".h", ".sh", ".txt", ".toml")]
    docs = tracked("*.md")
    paths = {f.relative_to(ROOT).as_posix() for f in docs}
    names = {f.name for f in docs}
    unresolved = []
    for source in sources:
        rel = source.relative_to(ROOT).as_posix()
        for cited in sorted(cited_files(source.read_text(errors="replace"))):
            if cited in paths or f"docs/{cited}" in paths or Path(cited).name in names:
                continue
            unresolved.append(f"{rel}: {cited}")
    assert unresolved == []


def test_the_method_page_describes_every_repair_the_code_cites():
    method = (ROOT / "docs" / "method.md").read_text()
    described = {int(n) for n in re.findall(r"^(\d)\. \*\*", method, re.M)}
    sources = tracked("core/**", "server/**", "tests/cpp/**")
    cited = set()
    for source in sources:
        cited |= {int(n) for n in re.findall(r"\b[Rr]epairs? (\d)\b", source.read_text())}
    assert cited and cited <= described == {1, 2, 3, 4, 5, 6}
