"""fTetWild's progress read from what it prints (tetwild.RunProgress): its stages in order,
the optimization moving as the worst energy falls, a fraction that never goes back and stays
below 1; and a real run's polls moving through its stages rather than jumping at its end."""

from __future__ import annotations

import numpy as np
import pytest
from build_test_support import icosphere
from hapticut.scenebuild import tetwild
from hapticut.scenebuild.geometry import enclosure_surface
from hapticut.scenebuild.tetwild import RunProgress, TetWildParams

# What fTetWild prints through a run (its own words, cut short), one stage after another.
PREPARING = ["Starting tetrahedralization...", "Loading mesh...", "collapsing 0.007175"]
INSERTING = ["Tetrahedralization performed.", "#boundary_e1 = 0"]
OPTIMIZING_START = ["initializing...", "#v = 3135", "#t = 16121", "max_energy = 1000"]
PASS = ["//////////////// pass {n} ////////////////", "edge splitting...", "success = 10479"]
FINISHING = ["//////////////// postprocessing ////////////////", "edge collapsing..."]
DONE = ["Tetrahedralization completed. Extracting mesh data..."]


def fed(progress: RunProgress, lines: list[str], pieces: int = 3) -> list[float]:
    """The fraction after each piece of the lines, fed cut at arbitrary places."""
    text = "".join(line + "\n" for line in lines)
    cuts = np.linspace(0, len(text), pieces + 1).astype(int)
    seen = []
    for start, end in zip(cuts[:-1], cuts[1:], strict=True):
        progress.feed(text[start:end])
        seen.append(progress.at(0.0))
    return seen


def stage_start(name: str) -> float:
    return next(mark for _, stage, mark, _ in RunProgress.STAGES if stage == name)


def test_the_stages_are_read_in_order_and_the_fraction_never_goes_back():
    progress = RunProgress(stop_energy=10.0, max_passes=80)
    seen = [progress.at(0.0)]
    for lines, stage in [
        (PREPARING, "preparing the surfaces"),
        (INSERTING, "inserting the surfaces"),
        (OPTIMIZING_START, "optimizing"),
        (FINISHING, "finishing"),
        (DONE, "filtering"),
    ]:
        seen += fed(progress, lines)
        assert progress.stage == stage
        assert seen[-1] >= stage_start(stage)
    assert seen == sorted(seen) and seen[-1] < 1.0


def test_the_optimization_moves_as_the_worst_energy_falls_to_the_stop_energy():
    """From 1000 to 10 on a log scale: 100 is half of the stage, 10 nearly all of it."""
    progress = RunProgress(stop_energy=10.0, max_passes=80)
    fed(progress, PREPARING + INSERTING + OPTIMIZING_START)
    start, end = stage_start("optimizing"), stage_start("finishing")
    halfway = fed(progress, [PASS[0].format(n=0), "max_energy = 100"], pieces=1)[-1]
    assert halfway == pytest.approx(start + (end - start) * RunProgress.WITHIN * 0.5, abs=0.01)
    near_end = fed(progress, [PASS[0].format(n=1), "max_energy = 10"], pieces=1)[-1]
    assert near_end == pytest.approx(start + (end - start) * RunProgress.WITHIN, abs=0.01)
    assert near_end < end


def test_between_lines_it_creeps_but_stays_within_its_stage():
    progress = RunProgress(stop_energy=10.0, max_passes=80)
    fed(progress, PREPARING + INSERTING)
    quiet = [progress.at(seconds) for seconds in (0.0, 1.0, 10.0, 1000.0)]
    assert quiet == sorted(quiet) and quiet[0] < quiet[-1] < stage_start("optimizing")
    # A line read after a long creep does not take the fraction back.
    assert fed(progress, ["#boundary_e2 = 0"], pieces=1)[-1] >= quiet[-1]


def test_a_real_run_moves_through_its_stages_before_it_ends():
    vertices, faces = icosphere(30.0, 3)
    box_vertices, box_faces = enclosure_surface("box", vertices.min(0), vertices.max(0), 5.0)
    polled: list[tuple[float, str]] = []
    tetwild.tetrahedralize(
        np.concatenate([box_vertices, vertices]),
        np.concatenate([box_faces, faces + len(box_vertices)]),
        TetWildParams(edge_length_mm=6.0, envelope_mm=0.3, coarsen=True),
        poll=lambda elapsed_s, fraction, stage: polled.append((fraction, stage)),
    )
    fractions = [f for f, _ in polled]
    stages = list(dict.fromkeys(s for _, s in polled))
    assert fractions == sorted(fractions) and fractions[-1] < 1.0
    assert {"optimizing", "finishing"} <= set(stages)
    assert stages == [s for _, s, _, _ in RunProgress.STAGES if s in stages]
    # Before fTetWild returned, the polls had reached its last stages (the coarsening takes
    # many polls): the bar moved with the run rather than waiting for its end.
    assert fractions[-1] >= stage_start("finishing")
