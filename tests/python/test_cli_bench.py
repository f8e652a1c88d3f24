"""`hapticut bench` as a user runs it: a table beside the paper's Table 2."""

import subprocess
import sys


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "hapticut.cli", *args], capture_output=True, text=True, timeout=300
    )


def test_bench_transitions_prints_every_row_of_table2():
    result = run_cli("bench", "transitions", "--repeats", "20", "--batches", "1")
    assert result.returncode == 0, result.stderr
    rows = [line for line in result.stdout.splitlines() if line.startswith("|")]
    assert len(rows) == 2 + 24  # header, rule, 24 timed cells
    assert "489.3" in result.stdout and "50.7" in result.stdout  # the paper's figures beside ours
    assert rows[2].split("|")[5].strip() not in ("", "-")  # our ns column has a figure


def test_bench_rejects_an_unknown_benchmark():
    result = run_cli("bench", "nonsense")
    assert result.returncode == 2
    assert "invalid choice" in result.stderr
