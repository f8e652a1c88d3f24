"""The engine through hapticut._core: arrays in, arrays out, errors named."""

import numpy as np
import pytest
from hapticut import _core, engine

FREE = {"name": "air", "model": "free"}
DRAG = {"name": "flesh", "model": "drag", "drag_distance_mm": 1.0}
RIGID = {"name": "bone", "model": "rigid"}


def grid_space(labels_of=None, jitter=0.2):
    vertices, tets = _core.grid_mesh([0, 10, 20, 30], [0, 10, 20, 30], [0, 10, 20, 30], jitter, 5)
    centres = vertices[tets].mean(axis=1)
    labels = np.zeros(len(tets), np.int32) if labels_of is None else labels_of(centres)
    return _core.Space(vertices, tets, labels.astype(np.int32), [FREE, DRAG, RIGID])


def test_many_proxies_step_in_one_call_and_report_arrays():
    space = grid_space()
    proxies = _core.ProxySet(space, 4)
    start = np.array([[5, 5, 5], [25, 25, 25], [15, 5, 25], [40, 5, 5]], float)
    kinds = proxies.reset(start)
    assert kinds.tolist() == [0, 0, 0, 1]  # inside, inside, inside, outside
    target = start + [1.5, 0.5, -0.5]
    proxies.step(target, 0.001)
    np.testing.assert_allclose(proxies.q, target)
    assert proxies.state.tolist()[:3] == [int(_core.ProxyState.TET)] * 3
    assert proxies.force_N.shape == (4, 3)
    counters = proxies.counters
    assert counters["transitions"].shape == (4, 5, 5, 2)
    assert counters["ticks"].tolist() == [1, 1, 1, 1]
    assert proxies.check_invariants() == ["", "", "", ""]


def test_rigid_block_holds_proxies_on_its_surface():
    space = grid_space(lambda c: np.where(c[:, 2] < 10, 2, 0), jitter=0.0)
    proxies = _core.ProxySet(space, 2)
    proxies.reset(np.array([[12, 12, 15], [22, 13, 18]], float))
    path = np.linspace([[12, 12, 15], [22, 13, 18]], [[14, 16, 4], [21, 11, 2]], 50)
    q = proxies.run(np.ascontiguousarray(path), 0.001)
    assert q.shape == (50, 2, 3)
    assert np.all(q[:, :, 2] >= 10 - 1e-6), "a proxy went into the bone"
    np.testing.assert_allclose(q[-1, :, 2], 10.0, atol=1e-9)
    np.testing.assert_allclose(proxies.force_N[:, 2], 0.1 * (10 - path[-1, :, 2]), atol=1e-9)
    assert set(proxies.state.tolist()) <= {int(_core.ProxyState.FACE), int(_core.ProxyState.EDGE)}


def test_drag_lag_is_d_along_a_stroke():
    space = grid_space(lambda c: np.ones(len(c), np.int32))
    proxies = _core.ProxySet(space, 1)
    path = np.linspace([3, 4, 5], [27, 24, 22], 400)[:, None, :]
    proxies.reset(path[0])
    q = proxies.run(np.ascontiguousarray(path), 0.001)
    lag = np.linalg.norm(q[50:, 0] - path[50:, 0], axis=1)
    np.testing.assert_allclose(lag, 1.0, atol=1e-9)


def test_space_returns_its_mesh_as_stored():
    vertices, tets = _core.two_tets_mesh(10.0)
    inverted = tets.copy()
    inverted[:, [0, 1]] = inverted[:, [1, 0]]  # both tets now negatively oriented
    space = _core.Space(vertices, inverted, np.array([0, 1], np.int32), [FREE, DRAG])
    stored = space.tets
    assert stored.shape == (2, 4) and stored.dtype == np.int32
    assert space.stats["reoriented_tets"] == 2
    for original, kept in zip(inverted, stored, strict=True):
        assert sorted(original) == sorted(kept)
        a, b, c, d = vertices[kept]
        assert np.dot(b - a, np.cross(c - a, d - a)) > 0  # positively oriented
    np.testing.assert_array_equal(space.vertices, vertices)
    np.testing.assert_array_equal(space.tet_materials, [0, 1])
    assert space.material_names == ["air", "flesh"]


def test_bad_meshes_name_the_offending_index():
    vertices, tets = _core.two_tets_mesh(10.0)
    broken = vertices.copy()
    broken[3, 1] = np.nan
    with pytest.raises(_core.MeshError, match="vertex 3"):
        _core.Space(broken, tets, np.zeros(2, np.int32), [FREE])
    bad_tets = tets.copy()
    bad_tets[1, 2] = 42
    with pytest.raises(_core.MeshError, match="tet 1"):
        _core.Space(vertices, bad_tets, np.zeros(2, np.int32), [FREE])
    with pytest.raises(_core.MeshError, match="material 5"):
        _core.Space(vertices, tets, np.array([0, 5], np.int32), [FREE])
    with pytest.raises(ValueError, match="unknown material model"):
        _core.Space(vertices, tets, np.zeros(2, np.int32), [{"name": "x", "model": "jelly"}])


def test_non_finite_device_points_are_rejected_with_zero_force():
    space = grid_space(lambda c: np.where(c[:, 2] < 10, 2, 0))
    proxies = _core.ProxySet(space, 1)
    proxies.reset(np.array([[12.0, 12, 15]]))
    proxies.step(np.array([[12.0, 12, 5]]))
    assert proxies.force_N[0, 2] > 0
    proxies.step(np.array([[np.nan, 12, 5]]))
    assert proxies.force_N.tolist() == [[0.0, 0.0, 0.0]]
    assert proxies.counters["rejected_inputs"].tolist() == [1]
    assert np.isfinite(proxies.q).all()


def test_blade_stroke_sums_forces_and_torques():
    space = grid_space(lambda c: np.where(c[:, 2] < 10, 2, 0), jitter=0.0)
    # The paper's points: each its own exact spring k (q - p).
    blade = _core.Blade(space, [0, 0, 0], [10, 0, 0], 5, coupling="independent")
    poses = engine.straight_stroke([10, 15, 14], [10, 15, 8], speed_mm_per_s=100)
    blade.reset(poses[0])
    result = blade.run(poses, 0.001)
    assert result["force_N"].shape == (len(poses), 3)
    np.testing.assert_allclose(result["force_N"][-1], [0, 0, 5 * 0.1 * 2.0], atol=1e-9)
    # Lever arms 0, 2.5, ..., 10 mm along x, force +z: torque -y.
    np.testing.assert_allclose(result["torque_N_mm"][-1], [0, -25 * 0.2, 0], atol=1e-9)
    assert (
        engine.state_counts(blade.state)["FACE"]
        + engine.state_counts(blade.state)["EDGE"]
        + engine.state_counts(blade.state)["VERTEX"]
        == 5
    )


def test_straight_stroke_samples_at_the_rate():
    poses = engine.straight_stroke([0, 0, 0], [100, 0, 0], speed_mm_per_s=100, rate_Hz=1000)
    assert poses.shape == (1001, 7)
    np.testing.assert_allclose(np.diff(poses[:, 0]), 0.1)
    np.testing.assert_allclose(poses[:, 3:], [[1, 0, 0, 0]] * 1001)
    with pytest.raises(ValueError):
        engine.straight_stroke([0, 0, 0], [1, 0, 0], speed_mm_per_s=0)


def test_a_blade_remembers_its_cut_until_reset_cuts():
    # Flesh (drag 4 mm) cut to a tenth of its drag, in a slab 10 < x < 20 (docs/decisions.md,
    # "Cut memory"); one point through it and back out, twice, then once more after reset_cuts.
    flesh = {**DRAG, "drag_distance_mm": 4.0, "cut_to": "flesh_cut"}
    flesh_cut = {**DRAG, "name": "flesh_cut", "drag_distance_mm": 0.4}
    vertices, tets = _core.grid_mesh([0, 10, 20, 30], [0, 10, 20, 30], [0, 10, 20, 30], 0.2, 5)
    centres = vertices[tets].mean(axis=1)
    labels = np.where((centres[:, 0] > 10) & (centres[:, 0] < 20), 1, 0).astype(np.int32)
    space = _core.Space(vertices, tets, labels, [FREE, flesh, flesh_cut])
    blade = _core.Blade(space, [0, 0, 0], [0, 0, 0], 1, coupling="independent")
    path = np.linspace([2, 13.3, 14.1], [28, 13.3, 14.1], 2600)
    poses = np.ascontiguousarray(np.hstack([path, np.tile([1.0, 0, 0, 0], (len(path), 1))]))

    # Deep in the slab (15 < x < 19): the first stroke's point slid along the slab's jittered
    # face before it went in, so the slit strays from the line near the entry.
    deep = (path[:, 0] > 15) & (path[:, 0] < 19)

    def stroke() -> float:
        blade.reset(poses[0])
        return float(np.linalg.norm(blade.run(poses, 0.001)["force_N"], axis=1)[deep].max())

    assert stroke() == pytest.approx(0.1 * 4.0, abs=0.02)
    cut = blade.cut_tets
    assert len(cut) > 0 and set(labels[cut].tolist()) == {1}
    assert stroke() <= 0.1 * 0.4 + 1e-9  # Through its own slit: the cut variant.
    blade.reset_cuts()
    assert len(blade.cut_tets) == 0
    assert stroke() == pytest.approx(0.1 * 4.0, abs=0.02)
    np.testing.assert_array_equal(blade.cut_tets, cut)  # The same stroke, the same cut.
