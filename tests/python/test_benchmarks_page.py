"""docs/benchmarks.md is tools/benchmarks/page.md filled in by tools/benchmarks/page.py with
what `hapticut bench` prints: a quick run gives every benchmark's section its table with every
column explained, and the committed page is the template filled in, not edited by hand."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
COMMITTED = ROOT / "docs" / "benchmarks.md"


def _load_page_module():
    spec = importlib.util.spec_from_file_location(
        "benchmarks_page", ROOT / "tools/benchmarks/page.py"
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # Its dataclasses look their module up there.
    spec.loader.exec_module(module)
    return module


page = _load_page_module()


@pytest.fixture(scope="module")
def quick_page(tmp_path_factory) -> str:
    out = tmp_path_factory.mktemp("bench") / "benchmarks.md"
    started = time.monotonic()
    result = subprocess.run(
        [sys.executable, str(ROOT / "tools/benchmarks/page.py"), "--quick", "--out", str(out)],
        capture_output=True,
        text=True,
        check=False,
        cwd=ROOT,
    )
    assert result.returncode == 0, result.stderr
    text = out.read_text()
    print(f"quick page: {time.monotonic() - started:.1f} s")
    for bench in page.BENCHMARKS:
        print(_table(page.section(text, bench.heading)))
    return text


def _table(section_text: str) -> str:
    return "\n".join(line for line in section_text.splitlines() if line.startswith("|"))


def _check_structure(text: str) -> None:
    assert "${" not in text, "a placeholder was left unfilled"
    assert "cores shared with other work" in text
    assert page.COMMAND in text
    assert not page.MACHINE_PATH.search(text), "the page names the generating machine's paths"
    assert "site-packages" not in text
    for bench in page.BENCHMARKS:
        body = page.section(text, bench.heading)
        table = _table(body)
        lines = table.splitlines()
        assert len(lines) >= 3, f"'{bench.heading}' has no table with a row"
        assert set(lines[1]) <= set("|-: "), f"'{bench.heading}': second line is not a rule"
        assert f"    hapticut bench {bench.key}" in body, f"'{bench.heading}' names no command"
        assert page.unexplained(page.columns(table), body) == [], bench.heading


def test_a_quick_run_gives_every_benchmark_its_table_with_every_column_explained(quick_page):
    _check_structure(quick_page)
    assert "**A quick run**" in quick_page


def test_the_committed_page_has_every_table_with_every_column_explained():
    _check_structure(COMMITTED.read_text())
    assert "**A quick run**" not in COMMITTED.read_text()


def test_the_committed_page_is_the_template_filled_in():
    # Every line of page.md outside its placeholders, in order: an edit to the page by hand,
    # or to the template without regenerating, fails here.
    template = page.TEMPLATE.read_text()
    pieces = re.split(r"\$\{\w+\}", template.replace("$$", "$"))
    pattern = "(.*?)".join(re.escape(piece) for piece in pieces)
    assert re.fullmatch(pattern, COMMITTED.read_text(), re.S), (
        f"{COMMITTED} is not {page.TEMPLATE} filled in: regenerate it with `{page.COMMAND}`"
    )


def test_a_column_the_template_does_not_explain_stops_the_page(tmp_path, monkeypatch):
    printout = (
        "machine: x86_64, python 3.11\n"
        "| from | to | new column |\n|------|----|------------|\n| TET | TET | 1 |\n"
    )
    monkeypatch.setattr(page, "run_bench", lambda args: printout)
    monkeypatch.setattr(page, "BENCHMARKS", page.BENCHMARKS[:1])
    with pytest.raises(ValueError, match="column\\(s\\) new column .* not explained"):
        page.write_page(tmp_path / "benchmarks.md", quick=False)
    assert not (tmp_path / "benchmarks.md").exists()


def test_a_printout_without_a_table_is_refused():
    with pytest.raises(ValueError, match="no table"):
        page.split_output("machine: x86_64\nnothing measured\n")
