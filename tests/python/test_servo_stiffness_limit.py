"""The device's stiffness limit through the real servo binary over loopback: the example UDP
bridge behind `bridge:...,max_stiffness=K` and a sim stroke with `max_stiffness_N_per_mm`.
A scene stiffness above the limit is lowered to it (one stderr line at load), a `set` above
it is refused naming the limit, one below it is taken; the status, the stream and the
recording show the stiffness in force, and the engine stepped with it (offline check).
A rigid blade renders the sum of its points' springs, n k: the limit applies to that sum,
for independent points to one point's k."""

from __future__ import annotations

import time

import numpy as np
import pytest
from hapticut.servo_client import ServoError
from servo_test_support import (
    SPHERE,
    ServoProcess,
    connect,
    independent_scene,
    offline_check,
    read_recording,
    run_servo,
    scene_with_coupling,
)
from test_servo_devices import bridge_summary, free_udp_port, start_bridge

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial

SCENE_K = 0.1  # The sphere example's coupling stiffness (N/mm).
LIMIT = 0.05


def frame_stiffness(frames) -> np.ndarray:
    return np.array([float(f.blades["scalpel"]["block"]["stiffness_N_per_mm"]) for f in frames])


def test_bridge_stiffness_limit_lowers_the_scene_and_refuses_a_set_above(tmp_path):
    port = free_udp_port()
    device = f"scalpel=bridge:port={port},max_stiffness={LIMIT}"
    record = tmp_path / "limit.rec"
    scene = independent_scene(tmp_path / "sphere.hapticut.json")
    args = [str(scene), "--device", device, "--engage", "--ramp", "0.05", "--record", str(record)]
    with ServoProcess(args) as servo:
        client = connect(servo, ["scalpel"])
        client.subscribe(rate_Hz=200)
        status = client.status()
        bridge = start_bridge(port, "--duration", "3.0")
        before = []
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:  # until the engine renders a contact force
            before += client.poll_all()
            stepped = [f for f in before if int(f.blades["scalpel"]["block"]["step_kind"])]
            if any(np.linalg.norm(f.blades["scalpel"]["block"]["engine_force_N"]) > 0.02
                   for f in stepped):  # fmt: skip
                break
            time.sleep(0.005)
        with pytest.raises(ServoError, match=r"above the limit of 0\.05 N/mm of blade 'scalpel'"):
            client.set_parameters(stiffness_N_per_mm=0.2, shading=True)
        refused_status = client.status()
        client.set_parameters(stiffness_N_per_mm=0.04)
        after = []
        while bridge.poll() is None:
            after += client.poll_all()
            time.sleep(0.01)
        after += client.poll_all()
        summary = bridge_summary(bridge)
        taken_status = client.status()
        client.close()
        assert servo.stop() == 0

    lowered = [line for line in servo.stderr_lines if "stiffness" in line]
    assert lowered == [
        f"hapticut-servo: blade 'scalpel': the scene's stiffness {SCENE_K:g} N/mm is above "
        f"device '{device}''s limit of {LIMIT:g} N/mm; lowered to {LIMIT:g} N/mm"
    ]
    assert status["settings"]["stiffness_N_per_mm"] == SCENE_K  # what was asked
    assert status["blades"][0]["stiffness_N_per_mm"] == LIMIT  # what is in force
    assert status["blades"][0]["max_stiffness_N_per_mm"] == LIMIT
    # The refused set applied nothing (neither the stiffness nor the shading with it).
    assert refused_status["blades"][0]["stiffness_N_per_mm"] == LIMIT
    assert refused_status["settings"]["shading"] is False
    assert taken_status["blades"][0]["stiffness_N_per_mm"] == 0.04
    assert taken_status["settings"]["stiffness_N_per_mm"] == 0.04

    stepped = [f for f in before if int(f.blades["scalpel"]["block"]["step_kind"])]
    assert stepped, "the bridge never drove the engine: the test would prove nothing"
    assert np.all(frame_stiffness(before) == LIMIT)
    k_after = frame_stiffness(after)
    assert k_after[-1] == 0.04 and set(k_after.tolist()) <= {LIMIT, 0.04}
    assert summary["forces_received"] > 500 and summary["max_force_N"] > 0.02

    recording = read_recording(record)
    block = recording.blade("scalpel")["block"]
    k = block["stiffness_N_per_mm"]
    switched = int(np.argmax(k != LIMIT))
    assert switched > 0 and np.all(k[:switched] == LIMIT) and np.all(k[switched:] == 0.04)
    assert np.linalg.norm(block["engine_force_N"][:switched], axis=1).max() > 0.02
    # The engine stepped with the recorded (lowered) stiffness, bit for bit.
    assert offline_check(scene, recording, "scalpel") > 500


def test_sim_stiffness_limit_scales_with_a_slower_rate(tmp_path):
    """At 500 Hz the 1 kHz limit is halved: a baked stroke runs at 0.025 N/mm throughout."""
    record = tmp_path / "sim.rec"
    device = f"scalpel=sim:press-slide,max_stiffness_N_per_mm={LIMIT}"
    scene = independent_scene(tmp_path / "sphere.hapticut.json")
    result = run_servo(
        str(scene), "--device", device, "--rate", "500", "--as-fast-as-possible",
        "--exit-when-done", "--engage", "--record", str(record),
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert (
        f"blade 'scalpel': the scene's stiffness {SCENE_K:g} N/mm is above device '{device}''s "
        f"limit of 0.025 N/mm at 500 Hz ({LIMIT:g} N/mm at 1 kHz); lowered to 0.025 N/mm"
    ) in result.stderr
    recording = read_recording(record)
    block = recording.blade("scalpel")["block"]
    assert np.all(block["stiffness_N_per_mm"] == 0.025)
    assert np.linalg.norm(block["engine_force_N"], axis=1).max() > 0.02
    assert offline_check(scene, recording, "scalpel") == len(recording)


def test_no_stiffness_limit_keeps_the_scene_stiffness(tmp_path):
    """The default sim states no limit: no line, and a set well above the scene's is taken."""
    args = [str(SPHERE), "--device", "scalpel=sim", "--wait"]
    with ServoProcess(args) as servo:
        client = connect(servo, ["scalpel"])
        assert client.status()["blades"][0]["max_stiffness_N_per_mm"] == 0.0
        client.set_parameters(stiffness_N_per_mm=2.0)
        assert client.status()["blades"][0]["stiffness_N_per_mm"] == 2.0
        client.close()
        assert servo.stop() == 0
    assert not [line for line in servo.stderr_lines if "stiffness" in line]


STIFF_LIMIT = 0.5  # N/mm at the device: the scene's 0.1 N/mm is fine for one point ...
POINTS = 50  # ... but the sphere's rigid blade of 50 points would render 5 N/mm.


def test_a_rigid_blade_is_lowered_to_the_limit_over_its_points(tmp_path):
    scene = scene_with_coupling(tmp_path / "rigid.hapticut.json", "rigid")
    record = tmp_path / "rigid.rec"
    device = f"scalpel=sim:press,max_stiffness_N_per_mm={STIFF_LIMIT}"
    result = run_servo(
        str(scene), "--device", device, "--as-fast-as-possible", "--exit-when-done",
        "--engage", "--record", str(record),
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert (
        f"blade 'scalpel': the scene's stiffness {SCENE_K:g} N/mm is above device '{device}''s "
        f"limit of 0.01 N/mm per point (a rigid blade of {POINTS} points renders {POINTS} k: "
        f"the device's {STIFF_LIMIT:g} N/mm over {POINTS}); lowered to 0.01 N/mm"
    ) in result.stderr
    recording = read_recording(record)
    assert recording.coupling("scalpel") == "rigid"
    block = recording.blade("scalpel")["block"]
    assert np.all(block["stiffness_N_per_mm"] == STIFF_LIMIT / POINTS)
    # Pressed on the ball, the whole edge pushes back: n k, not one point's k, per mm.
    assert np.linalg.norm(block["engine_force_N"], axis=1).max() > 0.02
    assert offline_check(scene, recording, "scalpel") == len(recording)


def test_a_rigid_blade_set_within_the_limit_per_point_but_over_it_in_sum_is_refused(tmp_path):
    scene = scene_with_coupling(tmp_path / "rigid.hapticut.json", "rigid")
    device = f"scalpel=sim:max_stiffness_N_per_mm={STIFF_LIMIT}"
    with ServoProcess([str(scene), "--device", device, "--wait"]) as servo:
        client = connect(servo, ["scalpel"])
        blade = client.status()["blades"][0]
        # 0.02 N/mm is 1/25 of the device's limit, but 50 rigid points render 1 N/mm.
        with pytest.raises(
            ServoError,
            match=r"0\.02 N/mm is above the limit of 0\.01 N/mm per point \(a rigid blade of "
            r"50 points renders 50 k: the device's 0\.5 N/mm over 50\) of blade 'scalpel'",
        ):
            client.set_parameters(stiffness_N_per_mm=0.02)
        refused = client.status()
        client.set_parameters(stiffness_N_per_mm=0.008)
        taken = client.status()["blades"][0]
        client.close()
        assert servo.stop() == 0
    assert blade["coupling"] == "rigid"
    assert blade["max_stiffness_N_per_mm"] == STIFF_LIMIT / POINTS
    assert blade["device_max_stiffness_N_per_mm"] == STIFF_LIMIT
    assert blade["rendered_stiffness_N_per_mm"] == pytest.approx(STIFF_LIMIT)
    assert refused["settings"]["stiffness_N_per_mm"] == SCENE_K  # nothing applied
    assert taken["stiffness_N_per_mm"] == 0.008
    assert taken["rendered_stiffness_N_per_mm"] == pytest.approx(POINTS * 0.008)


def test_independent_points_are_held_to_one_points_k(tmp_path):
    """The same device and sphere with independent points: one point's k is within the
    limit, so the scene's is kept, and a set up to the limit is taken."""
    scene = independent_scene(tmp_path / "independent.hapticut.json")
    device = f"scalpel=sim:max_stiffness_N_per_mm={STIFF_LIMIT}"
    with ServoProcess([str(scene), "--device", device, "--wait"]) as servo:
        client = connect(servo, ["scalpel"])
        loaded = client.status()["blades"][0]
        client.set_parameters(stiffness_N_per_mm=0.4)
        taken = client.status()["blades"][0]
        client.close()
        assert servo.stop() == 0
    assert not [line for line in servo.stderr_lines if "stiffness" in line]
    assert loaded["coupling"] == "independent"
    assert loaded["max_stiffness_N_per_mm"] == STIFF_LIMIT
    assert loaded["stiffness_N_per_mm"] == SCENE_K
    assert taken["stiffness_N_per_mm"] == taken["rendered_stiffness_N_per_mm"] == 0.4
