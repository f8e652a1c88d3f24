"""The engine refuses what it cannot simulate, through the bindings as ValueError."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hapticut import _core

VERTICES, TETS = _core.two_tets_mesh(10.0)
AIR = {"name": "air", "model": "free"}


def space(materials=None, **settings):
    return _core.Space(VERTICES, TETS, np.zeros(2, np.int32), materials or [AIR], **settings)


@pytest.mark.parametrize("value", [math.nan, math.inf, -1.0, 0.0, 1e308])
def test_space_rejects_a_drag_material_that_would_make_q_nan(value):
    drag = {"name": "flesh", "model": "drag", "drag_distance_mm": value}
    with pytest.raises(ValueError, match=r"material 'flesh' \(drag\) drag_distance_mm: "):
        space([drag])


def test_space_rejects_missing_and_unknown_material_fields():
    with pytest.raises(ValueError, match="drag_distance_mm required"):
        space([{"name": "flesh", "model": "drag"}])
    with pytest.raises(ValueError, match="unknown field 'colour'"):
        space([{"name": "air", "model": "free", "colour": "blue"}])
    with pytest.raises(ValueError, match="unknown material model 'jelly'"):
        space([{"name": "x", "model": "jelly"}])


@pytest.mark.parametrize(
    ("setting", "value", "message"),
    [
        ("stiffness_N_per_mm", 0.0, "stiffness_N_per_mm: must be > 0, got 0"),
        ("stiffness_N_per_mm", -0.1, "stiffness_N_per_mm: must be > 0, got -0.1"),
        ("stiffness_N_per_mm", math.nan, "stiffness_N_per_mm: not a finite number"),
        ("stiffness_N_per_mm", 1e308, "stiffness_N_per_mm: must be <= 100, got 1e+308"),
        ("servo_rate_Hz", math.inf, "servo_rate_Hz: not a finite number"),
        ("max_transitions_per_tick", 1_000_000_000, "max_transitions_per_tick: must be <= 10000"),
        ("max_transitions_per_tick", 0, "max_transitions_per_tick: must be >= 1, got 0"),
        ("capped_tick_force_N", -1.0, "capped_tick_force_N: must be > 0, got -1"),
        ("tolerance_mm", 1e6, "tolerance_mm: must be <= 0.0001, got 1e+06"),
        ("tolerance_mm", math.nan, "tolerance_mm: not a finite number"),
        ("tolerance_mm", -1.0, "tolerance_mm: must be >= 0, got -1"),
    ],
)
def test_space_rejects_settings_outside_their_range(setting, value, message):
    with pytest.raises(ValueError, match=message.replace("+", r"\+")):
        space(**{setting: value})


def test_space_accepts_the_defaults_and_the_bounds():
    assert space().tet_count == 2
    assert space(stiffness_N_per_mm=100.0, tolerance_mm=0.0001).stiffness_N_per_mm == 100.0
