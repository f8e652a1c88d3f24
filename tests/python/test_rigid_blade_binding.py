"""The rigid blade through hapticut._core: the whole edge stops at bone."""

import numpy as np
import pytest
from hapticut import _core, engine

FREE = {"name": "air", "model": "free"}
RIGID = {"name": "bone", "model": "rigid"}
K = 0.1  # N/mm, the scene's default stiffness.


def bone_space():
    """A 4 mm grid with an 8 mm bone cube whose top is at z = 16, under x = 28..36."""
    axis_x = np.arange(0.0, 61.0, 4.0)
    axis_yz = np.arange(0.0, 25.0, 4.0)
    vertices, tets = _core.grid_mesh(axis_x, axis_yz[:5], axis_yz, 0.0, 5)
    c = vertices[tets].mean(axis=1)
    bone = (abs(c[:, 0] - 32) < 4) & (abs(c[:, 1] - 8) < 4) & (c[:, 2] > 8) & (c[:, 2] < 16)
    return _core.Space(vertices, tets, np.where(bone, 1, 0).astype(np.int32), [FREE, RIGID])


def press(blade, depth_mm):
    poses = engine.straight_stroke([30, 8, 18], [30, 8, 16 - depth_mm], speed_mm_per_s=100)
    blade.reset(poses[0])
    blade.run(poses, 0.001)
    return blade.step(poses[-1], 0.001)


def test_a_rigid_blade_rests_on_the_bone_and_pushes_with_every_point():
    space = bone_space()
    rigid = _core.Blade(space, [-20, 0, 0], [20, 0, 0], 20)  # Rigid and free: the defaults.
    assert rigid.coupling == "rigid" and rigid.orientation == "free"
    tick = press(rigid, 4.0)
    assert (rigid.q[:, 2] >= 16 - 1e-6).all()
    assert tick["force_N"][2] >= 0.95 * 20 * K * 4.0
    assert 1 <= tick["rigid_rounds"] <= _core.BLADE_MAX_RIGID_ROUNDS and not tick["unseated"]
    pose = rigid.ideal_pose
    assert pose.shape == (7,)
    np.testing.assert_allclose(pose[:3], [30, 8, 16], atol=1e-4)
    np.testing.assert_allclose(abs(pose[3]), 1.0, atol=1e-9)  # Level: no turn.
    # Each point's force is k (q - p), the ideal point against the device's.
    np.testing.assert_allclose(rigid.force_N, K * (rigid.q - rigid.p), atol=1e-12)
    assert rigid.blade_counters["rigid_rounds"] >= rigid.blade_counters["ticks"] - 1

    independent = _core.Blade(space, [-20, 0, 0], [20, 0, 0], 20, coupling="independent")
    assert independent.coupling == "independent"
    loose = press(independent, 4.0)
    assert (independent.q[:, 2] < 16 - 1e-6).sum() >= 14  # Only the points over the bone held.
    assert loose["force_N"][2] < 0.5 * 20 * K * 4.0


def test_orientation_and_coupling_are_checked_and_orientation_switches():
    space = bone_space()
    blade = _core.Blade(space, [-20, 0, 0], [20, 0, 0], 20, coupling="rigid", orientation="locked")
    assert blade.orientation == "locked"
    blade.orientation = "free"
    assert blade.orientation == "free"
    with pytest.raises(ValueError, match="coupling"):
        _core.Blade(space, [-20, 0, 0], [20, 0, 0], 20, coupling="stiff")
    with pytest.raises(ValueError, match="orientation"):
        blade.orientation = "loose"
