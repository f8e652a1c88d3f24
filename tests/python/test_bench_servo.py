"""``hapticut bench servo``: each row shows its best round and lists every round; the targets
line counts rows meeting a target in their best round and in every round. Then one short real
run of the servo binary on an example scene."""

from __future__ import annotations

import re

import numpy as np
import pytest
from hapticut.bench import servo
from servo_test_support import EXAMPLES

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial


def _cells(text: str, scene: str) -> list[list[str]]:
    """The table's rows of `scene`, as stripped cells."""
    rows = [[c.strip() for c in line.strip("|").split("|")] for line in text.splitlines()]
    return [r for r in rows if r[0] == scene]


def _row(points: int, rate_Hz: float, compute_p99: float, wake_p99: float, age_p99: float):
    stats = {
        "compute_us": {"p50": compute_p99 / 2, "p99": compute_p99, "max": compute_p99 * 2},
        "wake_latency_us": {"p50": 10.0, "p99": wake_p99, "max": wake_p99 * 3},
        "late_ticks": 0,
        "ticks": 1000,
        "send_age_us": {"p50": 100.0, "p99": 200.0},
    }
    bare = {"wake_latency_us": {"p50": 10.0, "p99": 100.0, "max": 300.0}, "realtime": "x"}
    ages = np.full(200, age_p99)
    return servo.Row("s", 80, points, rate_Hz, stats, bare, 120.0, ages)


def test_each_row_shows_its_best_round_and_the_targets_count_best_and_every_round():
    # Row 1 (50 points, 1 kHz, 20 µs = 2 % of its period): meets compute in round 2 only
    # (15 µs), wake in round 1 only, frame age in both. Row 2 (500 points, 10 kHz): meets
    # compute in both rounds, wake in neither, age in round 2 only.
    round_1 = [_row(50, 1000.0, 30.0, 110.0, 1.0), _row(500, 10000.0, 20.0, 150.0, 2.5)]
    round_2 = [_row(50, 1000.0, 15.0, 130.0, 1.5), _row(500, 10000.0, 24.0, 140.0, 1.9)]
    text = servo.render([round_1, round_2])
    cells = _cells(text, "s")
    assert len(cells) == 2
    assert cells[0][4] == "7.5 / 15.0 / 30"  # compute from round 2
    assert cells[0][5] == "1.5 %" and cells[0][6] == "3.0 1.5"
    assert cells[0][9] == "1.10" and cells[0][10] == "1.10 1.30"  # wake from round 1
    assert cells[1][5] == "20.0 %" and cells[1][6] == "20.0 24.0"
    assert cells[1][9] == "1.40" and cells[1][13].endswith("/ 1.90")  # age from round 2
    targets = text.splitlines()[-1]
    assert targets.startswith("targets met, best of 2 round(s): ")
    assert "50 points at 1 kHz, compute p99 < 2 %: 1/1" in targets
    assert "500 points at 10 kHz, compute p99 < 25 %: 1/1" in targets
    assert "wake p99 <= 1.2x the bare loop: 1/2" in targets
    assert "frame age p99 < 2 ms: 2/2" in targets
    assert targets.endswith("(in every round: 0/1, 1/1, 0/2, 1/2)")


def test_a_short_real_run_on_an_example_scene():
    text = servo.run(duration_s=0.3, scenes=[EXAMPLES / "sphere80.hapticut.msgpack"], rounds=2)
    rows = _cells(text, "sphere80")
    assert len(rows) == 4, text  # 50 and 500 points, 1 and 10 kHz
    for cells in rows:
        line = " | ".join(cells)
        shares = [float(x) for x in cells[6].split()]
        assert len(shares) == 2 and all(0 < x < 1000 for x in shares), line
        assert float(cells[5].rstrip(" %")) == min(shares)
        ratios = [float(x) for x in cells[10].split()]
        assert len(ratios) == 2 and float(cells[9]) == min(ratios), line
        late, ticks = (int(x) for x in cells[11].split(" / "))
        assert ticks > 0 and 0 <= late <= ticks
        assert float(cells[12]) > 0  # frames arrived
    assert re.search(r"targets met, best of 2 round\(s\): .*\(in every round: ", text)
