"""The evaluation's timing harness: timed passes run on copies and leave
the methods as they were, the recorded pass is the same with or without timing,
and the matched-accuracy comparison picks the fastest model that is at least as
accurate. Never asserts a time, only that times are measured at all."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("hapticut._core")

from hapticut_evaluation import (  # noqa: E402
    _baselines,
    accuracy,
    meshes,
    methods,
    paths,
    report,
)


@pytest.fixture(scope="module")
def scene():
    # A Kuhn grid with a rigid block in the middle: no fTetWild needed.
    axis = np.linspace(-45.0, 45.0, 7)
    return meshes.grid_scene("block", axis, axis, axis, ((-15, -15, -15), (15, 15, 15)))


@pytest.fixture(scope="module")
def stroke():
    path, _ = paths.press_and_slide(0.001, points=4, radius_mm=15.0, slide_s=0.2)
    return path


def method_sets(scene, path):
    space = scene.space()
    sv, st = _baselines.rigid_surface(space)
    return [
        methods.start(_baselines.TetMethodSet(space, path.shape[1]), path),
        methods.start(_baselines.GodObjectSet(sv, st, path.shape[1]), path),
    ]


def test_timed_passes_leave_the_methods_where_they_were(scene, stroke):
    for method_set in method_sets(scene, stroke):
        before_q, before_force = method_set.q.copy(), method_set.force_N.copy()
        ns = method_set.time(stroke, 0.001, repeats=2)
        assert math.isfinite(ns) and ns > 0.0
        assert method_set.timed_nonfinite_passes == 0
        np.testing.assert_array_equal(method_set.q, before_q)
        np.testing.assert_array_equal(method_set.force_N, before_force)


def test_recorded_pass_does_not_depend_on_timing(scene, stroke):
    timed, untimed = method_sets(scene, stroke), method_sets(scene, stroke)
    for a, b in zip(timed, untimed, strict=True):
        with_timing = a.run(stroke, 0.001, timing_repeats=3)
        without = b.run(stroke, 0.001, timing_repeats=0)
        assert with_timing["ns_per_update"] > 0.0
        assert without["ns_per_update"] == 0.0
        np.testing.assert_array_equal(with_timing["q"], without["q"])
        np.testing.assert_array_equal(with_timing["force_N"], without["force_N"])
        # The stroke presses into the block: the proxy is held on its surface.
        assert np.abs(without["force_N"]).max() > 0.0


def test_round_robin_times_every_method(scene, stroke):
    sets = method_sets(scene, stroke)
    ns = accuracy.time_round_robin(sets, stroke, 0.001, repeats=2)
    assert len(ns) == len(sets)
    assert all(math.isfinite(x) and x > 0.0 for x in ns)


def _row(method, faces, ns, error):
    return {"method": method, "faces": faces, "rate_Hz": 1000.0, "ns_per_update": ns,
            "dir_err_mean_deg": error}  # fmt: skip


def test_matched_accuracy_takes_the_fastest_model_at_least_as_accurate():
    rows = [
        _row(methods.GOD, 80, 300.0, 9.0),
        _row(methods.GOD, 5120, 600.0, 1.3),
        _row(methods.TET, 80, 20.0, 8.9),
        _row(methods.TET, 5120, 60.0, 1.25),
        _row(methods.SHADED, 80, 50.0, 0.04),
        _row(methods.TET, 320, 10.0, 9.5),  # Faster, but less accurate than any god row.
    ]
    matched = {god["faces"]: (ours, ratio) for god, ours, ratio in report.matched_accuracy(rows)}
    ours, ratio = matched[80]
    assert (ours["method"], ours["faces"]) == (methods.TET, 80)
    assert ratio == pytest.approx(15.0)
    ours, ratio = matched[5120]
    assert (ours["method"], ours["faces"]) == (methods.SHADED, 80)
    assert ratio == pytest.approx(12.0)


def test_matched_accuracy_leaves_out_a_model_nothing_of_ours_matches():
    rows = [_row(methods.GOD, 80, 300.0, 0.01), _row(methods.TET, 80, 20.0, 8.9)]
    assert report.matched_accuracy(rows) == []
