"""What the servo and the add-on need from the engine's bindings:
checked inputs (never a crash), settings per tick, force shading, snapshots,
Spaces kept alive by their users, and the GIL released in long calls."""

import gc
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import numpy as np
import pytest
from hapticut import _core, engine

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
FREE = {"name": "air", "model": "free"}
RIGID = {"name": "bone", "model": "rigid"}


def bone_floor_space():
    """Bone below z = 10 in a free 30 mm box."""
    vertices, tets = _core.grid_mesh([0, 10, 20, 30], [0, 10, 20, 30], [0, 10, 20, 30], 0.0, 5)
    labels = np.where(vertices[tets].mean(axis=1)[:, 2] < 10, 1, 0).astype(np.int32)
    return _core.Space(vertices, tets, labels, [FREE, RIGID])


def run_python(code: str) -> subprocess.CompletedProcess:
    """Runs code in a fresh interpreter: a crash shows as a signal, not as a dead test run."""
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=120
    )


PRELUDE = """
    import numpy as np
    from hapticut import _core
    vertices, tets = _core.grid_mesh([0, 10, 20], [0, 10, 20], [0, 10, 20], 0.0, 5)
    labels = np.zeros(len(tets), np.int32)
    space = _core.Space(vertices, tets, labels, [{"name": "a", "model": "free"}])
"""


@pytest.mark.parametrize(
    ("call", "error"),
    [
        ("s.set_place(5, _core.ProxyState.TET, 0, 0, np.zeros(3))", "IndexError"),
        ("s.set_place(0, _core.ProxyState.TET, 10**6, 0, np.zeros(3))", "ValueError"),
        ("s.set_place(0, _core.ProxyState.FACE, 0, 7, np.zeros(3))", "ValueError"),
        ("s.set_place(0, _core.ProxyState.EDGE, -5, 0, np.zeros(3))", "ValueError"),
        ("s.set_place(0, _core.ProxyState.OUTSIDE, 3, 0, np.zeros(3))", "ValueError"),
        (
            "_core.time_transition(space, _core.ProxyState.TET, 10**6, 0, np.zeros(3), np.ones(3))",
            "ValueError",
        ),
        (
            "_core.time_transition(space, _core.ProxyState.VERTEX, 0, 9, np.zeros(3), np.ones(3))",
            "ValueError",
        ),
    ],
)
def test_indices_out_of_range_raise_instead_of_crashing(call, error):
    result = run_python(
        PRELUDE
        + f"""
    s = _core.ProxySet(space, 2)
    s.reset(np.array([[5.0, 5, 5], [6, 6, 6]]))
    try:
        {call}
        s.step(np.array([[7.0, 7, 7], [8, 8, 8]]))
        print("accepted")
    except Exception as e:
        print(type(e).__name__, e)
    """
    )
    assert result.returncode == 0, f"crashed ({result.returncode}): {result.stderr[-500:]}"
    assert result.stdout.startswith(error), result.stdout


@pytest.mark.parametrize("points", [0, -3, 10001, 2**31 - 1, 2**40])
def test_blade_point_count_is_bounded_and_named(points):
    space = bone_floor_space()
    with pytest.raises((ValueError, TypeError), match=str(points) if points < 2**31 else None):
        _core.Blade(space, [0, 0, 0], [10, 0, 0], points)
    assert _core.BLADE_MAX_POINTS == 10000


def test_zero_quaternion_is_an_error_in_reset_and_a_rejected_tick_in_step():
    space = bone_floor_space()
    blade = _core.Blade(space, [0, 0, 0], [10, 0, 0], 5)
    with pytest.raises(ValueError, match="quaternion"):
        blade.reset(np.array([10, 15, 15, 0, 0, 0, 0.0]))
    blade.reset(np.array([10, 15, 15, 1, 0, 0, 0.0]))
    poses = engine.straight_stroke([10, 15, 15], [10, 15, 8], 100.0)
    result = blade.run(poses)
    assert result["force_N"][-1, 2] > 0.3
    tick = blade.step(np.array([10, 15, 8, 0, 0, 0, 0.0]))
    assert tick["rejected"]
    np.testing.assert_array_equal(tick["force_N"], 0.0)
    assert blade.blade_counters["rejected_ticks"] == 1


def test_a_far_device_sample_is_a_rejected_input():
    """A glitch to 1e18 mm on sphere80 is refused and the sphere is felt after it."""
    _, space = engine.load_space(EXAMPLES / "sphere80.hapticut.msgpack")
    proxies = _core.ProxySet(space, 1)
    proxies.reset(np.array([[0.0, 0, 40]]))
    proxies.step(np.array([[0.0, 0, 1e18]]))
    assert proxies.last_rejected.tolist() == [True]
    assert proxies.counters["out_of_workspace_inputs"].tolist() == [1]
    proxies.step(np.array([[0.0, 0, 0]]))
    assert np.linalg.norm(proxies.force_N[0]) > 1.0
    assert proxies.check_invariants() == [""]
    with pytest.raises(ValueError, match="workspace"):
        proxies.reset(np.array([[0.0, 0, -1e18]]))


def test_settings_change_between_ticks_and_are_checked():
    space = bone_floor_space()
    proxies = _core.ProxySet(space, 1)
    proxies.reset(np.array([[15.0, 15, 15]]))
    proxies.run(np.ascontiguousarray(np.linspace([15, 15, 15], [15, 15, 8], 20)[:, None, :]))
    np.testing.assert_allclose(proxies.force_N[0], [0, 0, 0.2], atol=1e-9)
    settings = proxies.settings
    settings.stiffness_N_per_mm = 0.5
    proxies.settings = settings
    proxies.step(np.array([[15.0, 15, 8]]))
    np.testing.assert_allclose(proxies.force_N[0], [0, 0, 1.0], atol=1e-9)
    with pytest.raises(ValueError, match="stiffness"):
        settings.stiffness_N_per_mm = float("nan")
        proxies.settings = settings
    with pytest.raises(ValueError, match="max_transitions_per_tick"):
        _core.RuntimeSettings(max_transitions_per_tick=10**9)


def test_force_shading_in_proxy_set_and_blade():
    _, space = engine.load_space(EXAMPLES / "sphere80.hapticut.msgpack")
    shading = _core.ForceShading(space)
    start = np.array([[3.0, 2, 45], [-7, 4, 44]])
    path = np.ascontiguousarray(np.linspace(start, start - [0, 0, 22], 40))
    plain = _core.ProxySet(space, 2)
    shaded = _core.ProxySet(space, 2)
    settings = shaded.settings
    settings.force_shading = True
    shaded.settings = settings
    for s in (plain, shaded):
        s.reset(start)
        s.run(path)
    np.testing.assert_array_equal(plain.q, shaded.q)
    assert not np.allclose(plain.force_N, shaded.force_N)
    # The blade applies the same shading when its settings ask.
    blade = _core.Blade(space, [-5, 0, 0], [5, 0, 0], 3)
    blade_settings = blade.settings
    blade_settings.force_shading = True
    blade.settings = blade_settings
    blade.reset(np.array([3, 2, 45, 1, 0, 0, 0.0]))
    blade.run(engine.straight_stroke([3, 2, 45], [3, 2, 23], 200.0))
    snapshot = blade.snapshot()
    assert snapshot["force_N"].shape == (3, 3)
    assert snapshot["tick_index"] > 10
    assert np.linalg.norm(snapshot["force_N"]) > 0.5
    np.testing.assert_allclose(snapshot["force_N"], blade.force_N)
    del shading


def test_python_objects_keep_their_space_alive():
    """Loading a new scene while proxies of the old one exist cannot dangle."""
    space = bone_floor_space()
    proxies = _core.ProxySet(space, 1)
    # Independent points: their exact force k (q - p), the same as the ProxySet's, per point.
    blade = _core.Blade(space, [0, 0, 0], [10, 0, 0], 5, coupling="independent")
    proxies.reset(np.array([[15.0, 15, 15]]))
    blade.reset(np.array([10, 15, 15, 1, 0, 0, 0.0]))
    space = bone_floor_space()  # "A new scene": the old Space has no Python name left.
    gc.collect()
    proxies.run(np.ascontiguousarray(np.linspace([15, 15, 15], [15, 15, 8], 20)[:, None, :]))
    np.testing.assert_allclose(proxies.force_N[0], [0, 0, 0.2], atol=1e-9)
    result = blade.run(engine.straight_stroke([10, 15, 15], [10, 15, 8], 100.0))
    np.testing.assert_allclose(result["force_N"][-1], [0, 0, 1.0], atol=1e-9)


def test_long_calls_release_the_gil():
    """Another Python thread (Blender's UI) keeps running while Blade.run works."""
    _, space = engine.load_space(EXAMPLES / "sphere320.hapticut.msgpack")
    blade = _core.Blade(space, [-50, 0, 0], [50, 0, 0], 400)
    poses = engine.straight_stroke([0, -60, 0], [0, 60, 0], 20.0)  # 6000 ticks
    blade.reset(poses[0])
    inside = threading.Event()
    done = threading.Event()

    def work():
        inside.set()
        blade.run(poses)
        done.set()

    worker = threading.Thread(target=work)
    worker.start()
    inside.wait()
    beats = 0
    refused = 0
    while not done.is_set():
        beats += 1
        try:
            blade.q  # noqa: B018 (the access is the test)
        except RuntimeError as error:
            assert "in use by another thread" in str(error)
            refused += 1
        done.wait(0.0005)
    worker.join()
    assert beats > 20, f"the main thread ran only {beats} times during Blade.run"
    assert refused > 0, "a second thread reached the blade while it ran"
