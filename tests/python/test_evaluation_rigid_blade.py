"""The evaluation's rigid blade rows (tools/evaluation/hapticut_evaluation/rigid_blade.py):
stiffness against the length of edge over bone, the ideal edge's penetration, and force
shading on an example sphere."""

from pathlib import Path

import numpy as np
import pytest
from hapticut_evaluation import rigid_blade

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
FINGER = EXAMPLES / "finger.hapticut.msgpack"


def test_independent_points_grow_with_contact_and_the_rigid_blade_renders_every_spring():
    rows = rigid_blade.run_stiffness_vs_contact((1, 5, 50))
    whole = rigid_blade.POINTS * rigid_blade.K
    for row in rows:
        n = row["points_over_bone"]
        assert row["independent_points_N_per_mm"] == pytest.approx(n * rigid_blade.K, rel=1e-6)
        for key in ("rigid_free_N_per_mm", "rigid_locked_N_per_mm"):
            assert row[key] == pytest.approx(whole, rel=1e-3), (n, key)


def test_the_rigid_edge_never_enters_bone_where_independent_points_do():
    rows = rigid_blade.run_edge_penetration(FINGER, quick=True)
    scenes = {r["scene"] for r in rows}
    assert len(scenes) == 3
    for row in rows:
        assert row["ticks"] > 100 and row["edge_samples"] > 100 * row["ticks"]
        if row["method"].startswith("rigid"):
            assert row["edge_samples_in_bone"] == 0 and row["deepest_mm"] <= 1e-6, row
        else:  # The metric sees what the paper's points do: they wrap round and pass.
            assert row["edge_samples_in_bone"] > 0 and row["deepest_mm"] > 0.01, row


def test_depth_is_the_distance_to_the_bone_surface():
    space = rigid_blade.cylinder_space(radius_mm=4.0)
    rigid = np.asarray(space.tet_materials) == 1
    surface = rigid_blade.bone_surface(space, rigid)
    # The axis is 4 mm from the true cylinder; its faceted surface lies within a cell of it.
    depth = rigid_blade.depth_in_bone(np.array([0.0, 0.0, 0.0]), surface)
    assert 3.0 < depth <= 4.0 + 1e-9
    assert rigid_blade.depth_in_bone(np.array([0.0, 0.0, 3.0]), surface) < depth


def test_shading_turns_the_rigid_blades_force_to_the_sphere(monkeypatch):
    from hapticut_evaluation import economy

    monkeypatch.setattr(economy, "EXAMPLES_DIR", EXAMPLES)
    rows = rigid_blade.run_sphere_shading(("sphere80",), log=lambda _: None)
    assert [row["points"] for row in rows] == list(rigid_blade.SHADING_POINTS)
    for row in rows:
        assert row["contact_updates"] > 1000, row
        # The facets are felt; shaded, the force follows the sphere.
        assert row["plain_dir_err_smooth_mean_deg"] > 4.0, row
        assert row["shaded_dir_err_smooth_mean_deg"] < 0.25 * row["plain_dir_err_smooth_mean_deg"]
        assert row["shaded_dir_err_smooth_p95_deg"] < row["plain_dir_err_smooth_p95_deg"], row
