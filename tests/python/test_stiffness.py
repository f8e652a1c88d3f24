"""The stiffness a blade renders in contact: n k for a rigid blade, k for independent points."""

import pytest
from hapticut.stiffness import rendered_stiffness_N_per_mm


def test_a_rigid_blade_renders_its_points_springs_together():
    assert rendered_stiffness_N_per_mm(0.1, 50) == pytest.approx(5.0)
    assert rendered_stiffness_N_per_mm(0.1, 50, "rigid") == pytest.approx(5.0)
    assert rendered_stiffness_N_per_mm(0.1, 50, "independent") == 0.1
    assert rendered_stiffness_N_per_mm(0.1, 1, "rigid") == 0.1


def test_a_bad_coupling_or_point_count_is_refused():
    with pytest.raises(ValueError, match="coupling must be one of rigid, independent, got 'stiff'"):
        rendered_stiffness_N_per_mm(0.1, 50, "stiff")
    with pytest.raises(ValueError, match="at least 1 point, got 0"):
        rendered_stiffness_N_per_mm(0.1, 0)
