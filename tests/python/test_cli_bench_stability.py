"""`hapticut bench stability` as a user runs it: the installed C++ bench's table."""

import re
import subprocess
import sys


def test_bench_stability_prints_the_table_with_and_without_the_controller():
    result = subprocess.run(
        [sys.executable, "-m", "hapticut.cli", "bench", "stability"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    rows = [line for line in result.stdout.splitlines() if re.match(r"\|\s+\d", line)]
    assert len(rows) == 3 * 4 * 3  # rates x delays x stiffnesses
    rates = {float(row.split("|")[1]) for row in rows}
    delays = {float(row.split("|")[2]) for row in rows}
    assert rates == {250.0, 500.0, 1000.0}
    assert delays == {0.0, 1.0, 2.0, 5.0}
    without = [float(row.split("|")[4]) for row in rows]
    with_controller = [float(row.split("|")[6]) for row in rows]
    # Where the plain loop gives the hand energy, the controller gives less.
    assert any(energy > 0 for energy in without)
    for plain, controlled in zip(without, with_controller, strict=True):
        assert controlled <= max(plain, 0.0) + 1e-9
    summary = re.search(
        r"(\d+) of 36 cases without the controller, (\d+) of 36 with it", result.stdout
    )
    assert summary and int(summary.group(2)) < int(summary.group(1))
