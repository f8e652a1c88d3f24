"""`hapticut bench stability` as a user runs it: the installed C++ bench's two tables."""

import re
import subprocess
import sys


def table_rows(text):
    return [line.split("|")[1:-1] for line in text.splitlines() if re.match(r"\|\s+\d", line)]


def summary(text, cases):
    match = re.search(
        rf"(\d+) of {cases} cases without the controller, (\d+) of {cases} with it", text
    )
    assert match, text
    return int(match.group(1)), int(match.group(2))


def test_bench_stability_prints_the_servos_grid_and_the_stress_test():
    result = subprocess.run(
        [sys.executable, "-m", "hapticut.cli", "bench", "stability"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert result.returncode == 0, result.stderr
    main_text, stress_text = result.stdout.split("Stress test", 1)
    main, stress = table_rows(main_text), table_rows(stress_text)
    assert len(main) == len(stress) == 3 * 4 * 3  # rates x delays x stiffnesses
    for rows in (main, stress):
        assert {float(row[0]) for row in rows} == {250.0, 500.0, 1000.0}
        assert {float(row[1]) for row in rows} == {0.0, 1.0, 2.0, 5.0}
        without = [float(row[3]) for row in rows]
        with_controller = [float(row[5]) for row in rows]
        # Where the plain loop gives the hand energy, the controller gives less.
        assert any(energy > 0 for energy in without)
        for plain, controlled in zip(without, with_controller, strict=True):
            assert controlled <= max(plain, 0.0) + 1e-9

    # The main grid follows the servo's limit: 250 Hz gets a quarter of 1 kHz's stiffness.
    def stiffnesses(rows, rate):
        return sorted({float(row[2]) for row in rows if float(row[0]) == rate})

    fast = stiffnesses(main, 1000.0)
    assert fast == [0.5, 1.0, 2.0]  # A quarter, half and all of the test profile's 2 N/mm.
    assert stiffnesses(main, 250.0) == [k / 4 for k in fast]
    assert stiffnesses(main, 500.0) == [k / 2 for k in fast]
    plain, controlled = summary(main_text, 36)
    assert controlled == 0 < plain

    # The stress test: the absolute grid, rows above the servo's limit at their rate marked.
    # The test profile's 2 N/mm at 1 kHz allows 1 N/mm at 500 Hz and 0.5 N/mm at 250 Hz.
    above = {(250.0, 1.0), (250.0, 2.0), (500.0, 2.0)}
    for row in stress:
        mark = "yes" if (float(row[0]), float(row[2])) in above else "no"
        assert row[8].strip() == mark, row
    plain, controlled = summary(stress_text, 36)
    assert controlled < plain
    assert "Within the servo's limit at their rate (24 of 36 cases)" in stress_text


def test_stability_runs_the_stiffness_a_rigid_blade_renders():
    """A rigid blade's n point springs act together: the bench runs n k and marks it against
    the device's limit (the test profile's 2 N/mm at 1 kHz), the last column gives k back.
    Independent points render one k each."""
    from hapticut.bench import stability

    per_point = [0.01, 0.05]
    fast = ["--rates", "1000", "--delays", "0"]
    rigid = table_rows(stability.run(fast, points=50, point_stiffness=per_point))
    assert [float(row[2]) for row in rigid] == [0.5, 2.5]  # 50 x k
    assert [row[8].strip() for row in rigid] == ["no", "yes"]  # 2.5 N/mm is above 2 N/mm.
    assert [float(row[9]) for row in rigid] == per_point
    alone = table_rows(
        stability.run(fast, points=50, coupling="independent", point_stiffness=per_point)
    )
    assert [float(row[2]) for row in alone] == per_point
    assert [row[8].strip() for row in alone] == ["no", "no"]
    assert [float(row[9]) for row in alone] == per_point


def test_the_cli_takes_the_blade_and_refuses_a_bad_stiffness():
    result = subprocess.run(
        [sys.executable, "-m", "hapticut.cli", "bench", "stability", "--stiffness", "0,1"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 2 and "stiffnesses must be > 0 N/mm" in result.stderr
