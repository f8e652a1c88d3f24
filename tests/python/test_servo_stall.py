"""A late tick is a fault (docs/servo.md, "Safety"): the real servo binary, stopped with
SIGSTOP for over a second and continued, with each device kind that runs without hardware
(sim, replay, bridge, viewport). The tick after the stall writes zero force and does not
step the engine, the force ramps back in from zero, and no engine step in the whole run
spans more than the watchdog time. The recorded trace around the stall is printed."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
from servo_test_support import (
    EXAMPLES,
    SPHERE,
    ServoProcess,
    bake,
    connect,
    independent_scene,
    read_recording,
)

LATE_TICK = 1 << 15  # server/safety.h, kSafetyLateTick
FAULTS = (1 << 4) | (1 << 5) | (1 << 6) | (1 << 7) | (1 << 8) | (1 << 14) | LATE_TICK
WATCHDOG_S = 0.1  # --watchdog-ms, default
RAMP_S = 0.05
STALL_S = 1.5


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def stall(servo: ServoProcess, before_s: float = 1.0, after_s: float = 0.5) -> None:
    time.sleep(before_s)
    os.kill(servo.process.pid, signal.SIGSTOP)
    time.sleep(STALL_S)
    os.kill(servo.process.pid, signal.SIGCONT)
    time.sleep(after_s)


def check_trace(record, blade: str, kind: str, force_output: bool = True) -> None:
    recording = read_recording(record)
    dt = recording.ticks["dt_s"]
    block = recording.blade(blade)["block"]
    force = np.linalg.norm(block["force_N"], axis=1)
    # The stall is the one gap near its length; a loaded machine (ThreadSanitizer beside
    # other work) may leave shorter late ticks of its own, and each is a fault as well.
    late = np.flatnonzero(dt > WATCHDOG_S)
    stalled = late[dt[late] > STALL_S * 0.9]
    assert len(stalled) == 1, f"{kind}: ticks after a gap: {late}, dt {dt[late]}"
    flags = block["safety_flags"][late].astype(np.int64)
    assert np.all(flags & LATE_TICK), f"{kind}: a late tick is no fault: {late}, dt {dt[late]}"
    assert np.all(force[late] == 0.0) and np.all(block["step_kind"][late] == 0)
    k = int(stalled[0])
    print(f"\n{kind}: the stall's trace (tick, dt ms, step dt ms, |force| N, ramp, flags)")
    for i in range(max(0, k - 2), min(len(dt), k + 8)):
        print(
            f"  {i:6d} {dt[i] * 1e3:9.3f} {block['step_dt_s'][i] * 1e3:7.3f} "
            f"{force[i]:8.4f} {block['ramp'][i]:6.3f} {int(block['safety_flags'][i]):#07x}"
        )
    assert dt[k] > STALL_S * 0.9
    assert int(block["safety_flags"][k]) & LATE_TICK, f"{kind}: the stalled tick is no fault"
    assert force[k] == 0.0 and block["ramp"][k] == 0.0
    assert int(block["step_kind"][k]) == 0, f"{kind}: the engine stepped across the stall"
    assert block["step_dt_s"].max() <= WATCHDOG_S, f"{kind}: {block['step_dt_s'].max()} s"
    # Back in: from zero, each tick at most its own time's share of the ramp until it is
    # whole (a tick that starts late, as under ThreadSanitizer, takes a larger share).
    after = block["ramp"][k : k + 30]
    share = np.maximum(dt[k + 1 : k + 1 + len(after) - 1], 1e-3) / RAMP_S
    assert np.all(np.diff(after) <= share * 1.5 + 1e-9) or not force_output
    if force_output:
        assert force[k - 5 : k].max() > 0.0, f"{kind}: no force before the stall to test"


def test_a_stall_zeroes_the_force_of_a_sim_device(tmp_path):
    record = tmp_path / "sim.rec"
    args = [str(SPHERE), "--device", "sim:press,speed=20", "--engage", "--ramp", str(RAMP_S)]
    with ServoProcess([*args, "--record", str(record)]) as servo:
        stall(servo, before_s=1.5)
        assert servo.stop() == 0
    check_trace(record, "scalpel", "sim")


def test_a_stall_zeroes_the_force_of_a_replay(tmp_path):
    source = tmp_path / "source.rec"
    bake(SPHERE, source, "sim:press,speed=20")
    record = tmp_path / "replayed.rec"
    args = [str(SPHERE), "--device", f"replay:{source}", "--engage", "--ramp", str(RAMP_S)]
    with ServoProcess([*args, "--record", str(record)]) as servo:
        stall(servo)
        assert servo.stop() == 0
    check_trace(record, "scalpel", "replay", force_output=False)


def test_a_stall_zeroes_the_force_of_a_bridge(tmp_path):
    port = free_udp_port()
    record = tmp_path / "bridge.rec"
    scene = independent_scene(tmp_path / "sphere.hapticut.json")
    args = [str(scene), "--device", f"scalpel=bridge:port={port},max_force=0.5", "--engage"]
    args += ["--ramp", str(RAMP_S), "--record", str(record)]
    with ServoProcess(args) as servo:
        bridge = subprocess.Popen(
            [sys.executable, str(EXAMPLES / "bridge_example.py"), "--servo", f"127.0.0.1:{port}"]
            + ["--duration", "6"],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        stall(servo, before_s=1.5)
        assert servo.stop() == 0
        bridge.kill()
        bridge.wait(10)
    check_trace(record, "scalpel", "bridge")


def test_a_stall_zeroes_the_force_of_a_viewport_device(tmp_path):
    record = tmp_path / "viewport.rec"
    args = [str(SPHERE), "--device", "scalpel=viewport", "--engage", "--ramp", str(RAMP_S)]
    with ServoProcess([*args, "--record", str(record)]) as servo:
        client = connect(servo, ["scalpel"])
        done = threading.Event()

        def send_poses() -> None:
            # Input only: no force to zero, but the engine must not step across the stall.
            start = time.monotonic()
            while not done.is_set():
                z = max(5.0, 25.0 - 20.0 * (time.monotonic() - start))
                client.send_pose("scalpel", [0.0, 0.0, z, 1.0, 0.0, 0.0, 0.0])
                time.sleep(0.002)

        sender = threading.Thread(target=send_poses, daemon=True)
        sender.start()
        stall(servo, before_s=1.5)
        done.set()
        sender.join(5)
        client.close()
        assert servo.stop() == 0
    check_trace(record, "scalpel", "viewport", force_output=False)
