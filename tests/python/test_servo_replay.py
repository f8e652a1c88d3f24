"""Replay and several blades: a recording replayed gives bit-identical proxies, ideal poses
and forces; two blades on two devices are stepped in the same tick and both in the stream."""

from __future__ import annotations

import time

import numpy as np
import pytest
from servo_test_support import (
    REPLAYED_BLOCK_FIELDS,
    SPHERE,
    ServoProcess,
    bake,
    connect,
    offline_check,
    read_recording,
    scene_with_coupling,
    two_blade_scene,
)

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial


def replay_and_compare(scene, tmp_path) -> tuple:
    """A press-slide stroke with a NaN sample, baked and replayed; asserts the replay's
    proxies, ideal poses and engine forces are the original's bit for bit."""
    original = tmp_path / "original.rec"
    bake(scene, original, "scalpel=sim:press-slide,nan_at_s=0.3")
    replayed = tmp_path / "replayed.rec"
    stats = bake(scene, replayed, f"scalpel=replay:{original}")
    a = read_recording(original)
    b = read_recording(replayed)
    n = len(a)
    assert len(b) >= n and stats["ticks"] >= n
    ra, rb = a.blade("scalpel"), b.blade("scalpel")
    for name in ("q", "p", "state"):
        assert np.array_equal(ra[name], rb[name][:n]), name
    for name in REPLAYED_BLOCK_FIELDS:
        assert np.array_equal(ra["block"][name], rb["block"][name][:n], equal_nan=True), name
    # The NaN sample is replayed too, and refused again.
    assert (rb["block"]["events"][:n] & (1 << 6)).any()
    assert offline_check(scene, b, "scalpel") > 0
    return a, b


def test_replay_is_bit_identical(tmp_path):
    a, _ = replay_and_compare(SPHERE, tmp_path)
    stepped = a.blade("scalpel")["block"]["step_kind"] != 0
    assert stepped.any()
    if a.coupling("scalpel") == "independent":  # No common pose: the device's.
        ideal = a.ideal_pose("scalpel")[stepped]
        assert np.array_equal(ideal[:, :3], a.blade("scalpel")["block"]["pose"][stepped, :3])


def test_a_rigid_blades_replay_is_bit_identical(tmp_path):
    """The rigid blade's ideal pose is recorded and replayed bit for bit; pressed onto the
    ball it rests above the device, on it."""
    scene = scene_with_coupling(tmp_path / "rigid.hapticut.json", "rigid")
    a, _ = replay_and_compare(scene, tmp_path)
    assert a.coupling("scalpel") == "rigid"
    block = a.blade("scalpel")["block"]
    stepped = block["step_kind"] != 0
    lift = a.ideal_pose("scalpel")[stepped, 2] - block["pose"][stepped, 2]
    assert lift.max() > 1.0 and lift.min() > -1e-9


def test_replay_of_a_missing_blade_is_named(tmp_path):
    original = tmp_path / "original.rec"
    bake(SPHERE, original, "scalpel=sim:press")
    from servo_test_support import run_servo

    result = run_servo(str(SPHERE), "--device", f"scalpel=replay:{original},blade=nope")
    assert result.returncode == 4
    assert "no blade 'nope'" in result.stderr and "scalpel" in result.stderr


def test_two_blades_on_two_devices(tmp_path):
    scene = two_blade_scene(tmp_path / "two.hapticut.json")
    record = tmp_path / "two.rec"
    bake(scene, record, "scalpel=sim:press-slide", "retractor=sim:press,speed=60")
    recording = read_recording(record)
    assert recording.blade_names == ["scalpel", "retractor"]
    for name in recording.blade_names:
        assert offline_check(scene, recording, name) == len(recording)
    scalpel = recording.blade("scalpel")["block"]["pose"]
    retractor = recording.blade("retractor")["block"]["pose"]
    assert not np.array_equal(scalpel, retractor)  # each follows its own device
    assert recording.blade("retractor")["q"].shape[1:] == (20, 3)

    # Both blades in every stream frame.
    args = [str(scene), "--device", "scalpel=sim", "--device", "retractor=viewport"]
    with ServoProcess(args) as servo:
        client = connect(servo, ["scalpel", "retractor"])
        client.subscribe(rate_Hz=120)
        client.send_pose("retractor", [0, 0, 40, 1, 0, 0, 0])
        time.sleep(0.3)
        frame = client.poll()
        assert frame is not None
        assert set(frame.blades) == {"scalpel", "retractor"}
        assert frame.blades["retractor"]["q"].shape == (20, 3)
        assert frame.blades["scalpel"]["q"].shape == (50, 3)


def test_a_blade_without_a_device_is_named(tmp_path):
    from servo_test_support import run_servo

    scene = two_blade_scene(tmp_path / "two.hapticut.json")
    result = run_servo(str(scene), "--device", "scalpel=sim")
    assert result.returncode == 4
    assert "blade 'retractor' has no device" in result.stderr
    result = run_servo(str(scene), "--device", "sim")
    assert result.returncode == 4 and "name one" in result.stderr
