"""The benchmarks run and find every Table 2 transition; times are printed, never asserted."""

import math

from hapticut.bench import blade, transitions


def test_every_table2_cell_has_a_setup_that_takes_that_transition():
    rows = transitions.measure(repeats=50, batches=1)
    assert len(rows) == len(transitions.PAPER_TABLE2_US)
    missing = [(r["from"], r["to"]) for r in rows if math.isnan(r["ns"])]
    assert missing == []
    text = transitions.render(rows)
    assert "VERTEX" in text and "speed-up" in text


def test_blade_benchmark_runs_on_the_generated_grid():
    space = blade._grid_space()
    assert 10_000 < space.tet_count < 14_000
    poses = blade.stroke_poses(space)
    result = blade.time_ticks(space, 50, poses[:100], repeats=1)
    assert len(result["tick_ns"]) == 100
    assert int(result["capped_points"].sum()) == 0
