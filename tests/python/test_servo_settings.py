"""Settings per tick over the control channel (stiffness, shading, work budget) and the
engine's own counters in the stream and the recording, with the real servo over loopback;
every recorded tick is checked against an offline engine run with the same settings."""

from __future__ import annotations

import time

import numpy as np
import pytest
from hapticut import engine
from hapticut.servo_client import ServoError
from servo_test_support import (
    SPHERE,
    ServoProcess,
    bake,
    connect,
    independent_scene,
    offline_check,
    read_recording,
    wait_stopped,
)
from test_servo_faults import assert_faulted_at, first_fault

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial

RIGID_SCENE = SPHERE  # A rigid body of flat facets: force shading bends its normals.


def test_stiffness_set_mid_stroke(tmp_path):
    record = tmp_path / "k.rec"
    args = [str(SPHERE), "--wait", "--engage", "--ramp", "0.05", "--exit-when-done"]
    args += ["--device", "scalpel=sim:press-slide,speed=60", "--record", str(record)]
    with ServoProcess(args) as servo:
        client = connect(servo, ["scalpel"])
        client.subscribe(rate_Hz=200)
        client.start()
        k_scene = None
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:  # until the blade is in contact
            frame = client.poll()
            if frame is not None:
                block = frame.blades["scalpel"]["block"]
                k_scene = float(block["stiffness_N_per_mm"])
                if np.linalg.norm(block["engine_force_N"]) > 0.05:
                    break
            time.sleep(0.005)
        assert k_scene is not None
        with pytest.raises(ServoError, match="stiffness"):
            client.set_parameters(stiffness_N_per_mm=-1.0)
        with pytest.raises(ServoError, match="shading"):
            client.set_parameters(shading="yes")
        client.set_parameters(stiffness_N_per_mm=3 * k_scene)
        frames = wait_stopped(client)
        client.close()
    streamed = [float(f.blades["scalpel"]["block"]["stiffness_N_per_mm"]) for f in frames]
    assert 3 * k_scene in streamed, "no frame carries the new stiffness"

    recording = read_recording(record)
    block = recording.blade("scalpel")["block"]
    k = block["stiffness_N_per_mm"]
    switched = np.nonzero(k != k_scene)[0]
    assert len(switched) > 100, "the stroke ended right after the change"
    first = int(switched[0])
    assert first > 0 and np.all(k[:first] == k_scene) and np.all(k[first:] == 3 * k_scene)
    assert np.linalg.norm(block["engine_force_N"][first - 1]) > 0.05
    # Bit for bit what an offline Blade gives with the same settings, tick by tick.
    assert offline_check(SPHERE, recording, "scalpel") == len(recording)

    # And three times what the scene's stiffness would give over the same path, where no
    # point kept a force of an earlier tick (the proxies do not depend on k).
    scene, space = engine.load_space(SPHERE)
    blade = engine.make_blade(space, scene.blades[0])
    ratios = []
    for t in range(len(recording)):
        pose = np.ascontiguousarray(block["pose"][t])
        if int(block["step_kind"][t]) == 2:
            blade.reset(pose)
        plain = blade.step(pose, float(block["step_dt_s"][t]))["force_N"]
        uncapped = block["capped_points"][t] == 0 and block["capped_points"][t - 1] == 0
        if t > first and uncapped and np.linalg.norm(plain) > 0.05:
            ratios.append(np.linalg.norm(block["engine_force_N"][t]) / np.linalg.norm(plain))
    assert len(ratios) > 50
    np.testing.assert_allclose(ratios, 3.0, rtol=1e-9)


def test_shading_and_work_budget_equal_an_offline_blade(tmp_path):
    record = tmp_path / "shaded.rec"
    # Force shading acts on independent points.
    scene = independent_scene(tmp_path / "sphere.hapticut.json", RIGID_SCENE)
    args = [str(scene), "--wait", "--engage", "--ramp", "0.05", "--exit-when-done"]
    args += ["--as-fast-as-possible", "--device", "scalpel=sim:press-slide,speed=40"]
    args += ["--record", str(record)]
    with ServoProcess(args) as servo:
        client = connect(servo, ["scalpel"])
        reply = client.set_parameters(shading=True, blade_transition_budget=20)
        assert reply["applied"] == {"shading": True, "blade_transition_budget": 20}
        settings = client.status()["settings"]
        assert settings["shading"] is True and settings["blade_transition_budget"] == 20
        client.start()
        wait_stopped(client)
        client.close()
    recording = read_recording(record)
    block = recording.blade("scalpel")["block"]
    assert np.all(block["force_shading"] == 1)
    stepped = offline_check(
        scene, recording, "scalpel", {"force_shading": True, "blade_transition_budget": 20}
    )
    assert stepped == len(recording)
    assert np.all(block["transitions"] <= 20)
    unfinished = int(np.count_nonzero(block["capped_points"] > 0))
    assert unfinished > 0, "the budget never ran out: the test would prove nothing"
    assert int(block["unfinished_ticks"][-1]) == unfinished

    # Shading changed the forces (else the comparison above proves nothing about it).
    with pytest.raises(AssertionError, match="force differs"):
        offline_check(
            scene,
            recording_without_shading(recording),
            "scalpel",
            {"blade_transition_budget": 20},
        )


def recording_without_shading(recording):
    """The same recording claiming every tick was unshaded."""
    import copy

    plain = copy.deepcopy(recording)
    plain.blade("scalpel")["block"]["force_shading"][:] = 0
    return plain


def test_absurd_sample_is_refused_by_the_engine_and_reported(tmp_path):
    record = tmp_path / "far.rec"
    device = "scalpel=sim:press-slide,far_at_s=0.3,far_ticks=3"
    stats = bake(SPHERE, record, device, extra=("--ramp", "0.05"))
    recording = read_recording(record)
    k = first_fault(recording, flag="outside_workspace")
    assert_faulted_at(recording, k)
    block = recording.blade("scalpel")["block"]
    assert list(block["engine_rejected"][k - 1 : k + 4]) == [0, 1, 1, 1, 0]
    assert int(block["rejected_ticks"][-1]) == 3 and int(block["out_of_workspace_ticks"][-1]) == 3
    assert int(block["rejected_ticks"][k - 1]) == 0
    assert np.all(block["force_N"][k : k + 3] == 0.0)
    assert np.linalg.norm(block["force_N"][k + 3 :], axis=1).max() > 0.05  # ramped up again
    blade = stats["blades"][0]
    assert blade["faults"] == 1 and blade["events"]["outside_workspace"] == 1
    assert offline_check(SPHERE, recording, "scalpel") == len(recording)


def test_engine_counters_and_zero_rotation_in_the_stream():
    args = [str(SPHERE), "--device", "scalpel=viewport", "--engage", "--watchdog-ms", "2000"]
    with ServoProcess(args) as servo:
        client = connect(servo, ["scalpel"])
        client.subscribe(rate_Hz=200)
        client.send_pose("scalpel", [0.0, 0.0, 100.0, 1.0, 0.0, 0.0, 0.0])
        time.sleep(0.1)
        client.send_pose("scalpel", [0.0, 0.0, 100.0, 0.0, 0.0, 0.0, 0.0])
        time.sleep(0.1)
        client.send_pose("scalpel", [1e7, 0.0, 100.0, 1.0, 0.0, 0.0, 0.0])
        time.sleep(0.1)
        client.send_pose("scalpel", [0.0, 0.0, 100.0, 1.0, 0.0, 0.0, 0.0])
        time.sleep(0.1)
        frames = client.poll_all()
        events = client.status()["blades"][0]["events"]
    assert events["engine_rejected"] == 1 and events["outside_workspace"] == 1
    last = frames[-1].blades["scalpel"]["block"]
    assert int(last["engine_rejected"]) == 0
    assert int(last["rejected_ticks"]) > 50 and int(last["out_of_workspace_ticks"]) > 0
    assert int(last["rejected_ticks"]) > int(last["out_of_workspace_ticks"])
