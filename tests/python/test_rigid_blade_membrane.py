"""A membrane the rigid blade has not broken holds the whole edge, as bone does; each point
breaks it when its own spring exceeds the break force."""

import numpy as np
from hapticut import _core, engine

K = 0.1  # N/mm, the scene's default stiffness.
BREAK_N = 0.6  # The membrane breaks under a point pressed 6 mm into it.
TOP = 16.0  # The membrane's top.


def skin_space(under_x: float):
    """A 4 mm grid; a 4 mm membrane slab (z 12..16) under x < under_x, air elsewhere."""
    axis_x = np.arange(0.0, 61.0, 4.0)
    axis_yz = np.arange(0.0, 25.0, 4.0)
    vertices, tets = _core.grid_mesh(axis_x, axis_yz[:5], axis_yz, 0.0, 5)
    c = vertices[tets].mean(axis=1)
    skin = (c[:, 0] < under_x) & (c[:, 2] > 12) & (c[:, 2] < 16)
    materials = [
        {"name": "air", "model": "free"},
        {"name": "skin", "model": "membrane", "break_force_N": BREAK_N},
    ]
    return _core.Space(vertices, tets, np.where(skin, 1, 0).astype(np.int32), materials)


def press(blade, depth_mm):
    poses = engine.straight_stroke([30, 8, 18], [30, 8, TOP - depth_mm], speed_mm_per_s=100)
    blade.reset(poses[0])
    blade.run(poses, 0.001)
    return blade.step(poses[-1], 0.001)


def test_a_membrane_under_one_end_holds_the_points_over_it_until_they_break_it():
    for orientation in ("free", "locked"):
        blade = _core.Blade(skin_space(22.0), [-20, 0, 0], [20, 0, 0], 20, orientation=orientation)
        press(blade, 4.0)  # Each point's spring: 0.4 N, below the break force.
        over = blade.q[:, 0] < 20.0
        assert over.sum() >= 4
        assert (blade.q[over, 2] >= TOP - 1e-6).all(), (orientation, blade.q[over, 2].min())
        if orientation == "locked":  # No tilt: the whole edge rests on the membrane.
            assert (blade.q[:, 2] >= TOP - 1e-6).all()
        else:  # The end over air goes down toward the device; the edge tilts.
            assert blade.q[-1, 2] < TOP - 2.0 and blade.q[0, 2] > TOP
        press(blade, 9.0)  # 0.9 N: the points over the membrane break it.
        assert (blade.q[over, 2] < TOP - 1.0).any(), orientation


def test_a_membrane_under_the_whole_blade_stops_it_level_with_every_spring():
    blade = _core.Blade(skin_space(61.0), [-20, 0, 0], [20, 0, 0], 20)
    tick = press(blade, 4.0)
    np.testing.assert_allclose(blade.q[:, 2], TOP, atol=1e-3)
    assert tick["force_N"][2] >= 0.95 * 20 * K * 4.0
    press(blade, 9.0)
    assert (blade.q[:, 2] < TOP - 1.0).all()


def test_independent_points_keep_the_papers_membrane():
    blade = _core.Blade(skin_space(30.0), [-20, 0, 0], [20, 0, 0], 20, coupling="independent")
    press(blade, 4.0)
    over = blade.q[:, 0] < 28.0
    assert (blade.q[over, 2] >= TOP - 1e-6).all()
    assert (blade.q[~over, 2] < TOP - 3.0).all()
