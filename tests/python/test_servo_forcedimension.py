"""The forcedimension device kind through the real servo binary, with the DHD stand-in
(server/devices/tests/dhd_standin.h, built with the C++ tests) loaded in place of Force
Dimension's library through $HAPTICUT_DHD_LIB: a session clamped, recorded and replayed,
with the sample-to-force latency measured; an error mid-session (force zero in that tick,
the device reopened, the force ramped back); the servo stalled (SIGSTOP) while pushing and
the device firmware's watchdog zeroing the force; a client's `load` binding an arm; the
errors of a missing library, no device, a device in use and one not initialised;
`--list-devices`, with and without the firmware's watchdog."""

from __future__ import annotations

import os
import signal
import time

import numpy as np
import pytest
from hapticut.servo_client import ServoError
from servo_test_support import SPHERE, ServoProcess, connect, independent_scene, run_servo
from standin_support import (
    DHD_STANDIN,
    DHD_STANDIN_NO_WATCHDOG,
    Call,
    Standin,
    built_standin,
    check_listed_without_library,
    check_lost_then_ramped_back,
    check_refused_at_start,
    check_session_recorded_and_replayed,
    counters,
    index_of,
    listing,
    load_and_run,
    print_sample_to_force,
    run_session,
    use_standin,
)

# Times a real servo's clock-paced threads: runs alone, never beside other tests.
pytestmark = pytest.mark.serial

MAX_FORCE_N = 0.5
BINDING = f"forcedimension:0,max_force={MAX_FORCE_N}"
# Down from 10 mm above the sphere's centre to 10 mm below it over 1000 reads (the SDK's
# frame, m), then held there, pushing.
DESCENT = "from=0:0:0.010,to=0:0:-0.010,reads=1000"
WATCHDOG_UNIT_S = 125e-6  # dhdSetWatchdog's unit
STALL_S = 0.3


@pytest.fixture
def standin(monkeypatch, tmp_path) -> Standin:
    return use_standin(
        monkeypatch, tmp_path, DHD_STANDIN, "HAPTICUT_DHD_LIB", "HAPTICUT_DHD_STANDIN"
    )


def scene_force(call: Call) -> tuple[float, float, float]:
    """A dhdSetForce call's force in the scene's axes: scene = (y, -x, z) of the SDK's."""
    x, y, z = call.args
    return (y + 0.0, -x + 0.0, z + 0.0)  # + 0.0: -0.0 compares as 0.0 in a set of tuples


def test_a_session_is_clamped_recorded_and_written_to_the_arm(standin, tmp_path):
    """The arm's position drives the blade, the force it gets is the recorded one in its own
    axes and within the clamp, force is enabled only after the limits are read and at zero,
    the recorded proxies equal an offline engine run of the recorded poses, and a replay of
    the recording gives them again bit for bit. Prints the sample-to-force latency the
    device measured: dhdGetPosition to the dhdSetForce of the same tick (not asserted)."""
    standin.script(f"type=33,{DESCENT}")
    scene = independent_scene(tmp_path / "sphere.hapticut.json")
    record = tmp_path / "dhd.rec"
    status = run_session(scene, record, BINDING, lambda s: counters(s).get("samples", 0) > 2000)
    blade = status["blades"][0]
    assert blade["kind"] == "forcedimension" and blade["passivity"] is True
    assert blade["device_error"] == ""
    found = counters(status)
    assert found["faults"] == 0 and found["forces_written"] > 2000
    print_sample_to_force("DHD", found)

    calls = standin.calls()
    limits, enable = index_of(calls, "dhdGetMaxForce"), index_of(calls, "dhdEnableForce")
    assert index_of(calls, "dhdOpenID") < index_of(calls, "dhdGetStatus") < limits < enable
    assert calls[enable].args[0] == 1.0  # DHD_ON
    forces = [c for c in calls if c.name == "dhdSetForce"]
    before = [c for c in calls[:enable] if c.name == "dhdSetForce"]
    assert all(c.args == (0.0, 0.0, 0.0) for c in before)
    assert calls[-3].name == "dhdSetForce" and calls[-3].args == (0.0, 0.0, 0.0)
    assert [c.name for c in calls[-2:]] == ["dhdStop", "dhdClose"]
    magnitudes = np.array([np.linalg.norm(c.args) for c in forces])
    assert 0.1 < magnitudes.max() <= MAX_FORCE_N + 1e-9
    pushed = [scene_force(c) for c in forces if any(c.args)]
    check_session_recorded_and_replayed(scene, record, pushed, MAX_FORCE_N)


def test_an_error_mid_session_zeroes_the_force_in_that_tick_and_ramps_back(standin, tmp_path):
    """A failed dhdGetPosition while pushing: a zero force in the same call, the device lost
    in that tick's record, nothing pushed until maintain() reopened it (limits read before the
    force is enabled again), then the force ramped back in."""
    standin.script(f"type=33,{DESCENT},fail_position_at=1500,fail_count=1")
    scene = independent_scene(tmp_path / "sphere.hapticut.json")
    record = tmp_path / "fault.rec"

    def reopened_and_pushing(status: dict) -> bool:
        return counters(status).get("reconnects", 0) >= 1 and counters(status)["samples"] > 2500

    status = run_session(scene, record, BINDING, reopened_and_pushing)
    assert counters(status)["faults"] == 1 and counters(status)["reconnects"] == 1
    assert status["blades"][0]["events"]["device_lost"] >= 1

    calls = standin.calls()
    failed = next(i for i, c in enumerate(calls) if c.name == "dhdGetPosition" and c.result < 0)
    zero = calls[failed + 1]
    assert zero.name == "dhdSetForce" and zero.args == (0.0, 0.0, 0.0)
    print(
        "\ntime to zero force after a failed dhdGetPosition in the servo: 0 ticks, "
        f"{(zero.time_s - calls[failed].time_s) * 1e6:.1f} us"
    )
    closed, reopened = index_of(calls, "dhdClose", failed), index_of(calls, "dhdOpenID", failed)
    limits, enabled = (
        index_of(calls, name, failed) for name in ("dhdGetMaxForce", "dhdEnableForce")
    )
    assert closed < reopened < limits < enabled
    between = [c for c in calls[failed + 1 : enabled] if c.name == "dhdSetForce"]
    assert all(c.args == (0.0, 0.0, 0.0) for c in between)
    pushing = [c for c in calls[:failed] if c.name == "dhdSetForce"][-1]
    assert np.linalg.norm(pushing.args) > 0.05, "not pushing at the fault: proves nothing"
    check_lost_then_ramped_back(record)


def applied_force(calls: list[Call], t: float) -> tuple[float, float, float]:
    """What the arm applies at `t` by the stand-in's record (its firmware model,
    dhd_standin.h): the last force commanded while forces are on, zero once the
    firmware's watchdog has passed since that command."""
    enabled, watchdog_s, last = False, 0.0, None
    for call in calls:
        if call.time_s > t:
            break
        if call.result < 0:
            continue
        if call.name == "dhdEnableForce":
            enabled = call.args[0] != 0.0
        elif call.name in ("dhdStop", "dhdClose", "firmware_watchdog"):
            enabled = False
        elif call.name == "dhdSetWatchdog":
            watchdog_s = call.args[0] * WATCHDOG_UNIT_S
        elif call.name == "dhdSetForce":
            last = call
    if not enabled or last is None or (watchdog_s > 0.0 and t - last.time_s > watchdog_s):
        return (0.0, 0.0, 0.0)
    return last.args


def test_a_stalled_servo_leaves_no_force_once_the_firmware_watchdog_expires(standin, tmp_path):
    """The servo stopped (SIGSTOP) for 0.3 s while pushing: nothing of ours runs, and the
    device firmware's watchdog, set at the start to --watchdog-ms as far as it goes (100 ms:
    its longest, 255 x 125 us) before the force was enabled, disables forces once no command
    came for that long. Once the servo runs again, forces are enabled again at zero before
    the first force, and the force ramps back in. Prints the time from the last force
    command to zero force on the arm."""
    standin.script(f"type=33,{DESCENT}")
    scene = independent_scene(tmp_path / "sphere.hapticut.json")
    args = [str(scene), "--device", f"scalpel={BINDING}", "--engage", "--ramp", "0.05"]
    with ServoProcess(args) as servo:
        client = connect(servo, ["scalpel"])

        def wait_for_samples(count: int) -> dict:
            deadline = time.monotonic() + 20.0
            status = client.status()
            while counters(status).get("samples", 0) < count and time.monotonic() < deadline:
                time.sleep(0.05)
                status = client.status()
            return status

        before = counters(wait_for_samples(1500))["samples"]  # Past the descent: pushing.
        os.kill(servo.process.pid, signal.SIGSTOP)
        time.sleep(STALL_S)
        os.kill(servo.process.pid, signal.SIGCONT)
        status = wait_for_samples(before + 1000)
        client.close()
        assert servo.stop() == 0
    found = counters(status)
    assert found["faults"] == 0 and found["firmware_watchdog_us"] == 31875
    assert found["forces_reenabled"] >= 1

    calls = standin.calls()
    armed = index_of(calls, "dhdSetWatchdog")
    assert calls[armed].args[0] == 255 and armed < index_of(calls, "dhdEnableForce")
    watchdog_s = 255 * WATCHDOG_UNIT_S
    # The stall: the longest gap between two force commands of the session.
    stop = index_of(calls, "dhdStop")
    forces = [i for i in range(stop) if calls[i].name == "dhdSetForce"]
    gaps = [calls[b].time_s - calls[a].time_s for a, b in zip(forces[:-1], forces[1:], strict=True)]
    k = int(np.argmax(gaps))
    last, after = forces[k], forces[k + 1]
    held = calls[last]
    assert gaps[k] > watchdog_s, "the servo did not stall past the watchdog: proves nothing"
    assert np.linalg.norm(held.args) > 0.05, "not pushing at the stall: proves nothing"
    # Within the duration the arm holds the last command; after it, nothing.
    assert applied_force(calls, held.time_s + watchdog_s - 1e-6) == held.args
    assert applied_force(calls, held.time_s + watchdog_s + 1e-6) == (0.0, 0.0, 0.0)
    assert applied_force(calls, calls[after].time_s - 1e-6) == (0.0, 0.0, 0.0)
    off = [c for c in calls[last:after] if c.name == "firmware_watchdog"]
    assert len(off) == 1 and off[0].args == held.args
    # Back: zero, forces on again, then the servo's (zero: its own watchdog tripped) and the ramp.
    assert calls[after].args == (0.0, 0.0, 0.0)
    assert calls[after + 1].name == "dhdEnableForce" and calls[after + 1].args[0] == 1.0
    assert max(np.linalg.norm(c.args) for c in calls[after:] if c.name == "dhdSetForce") > 0.05
    print(
        f"\nservo stalled {gaps[k] * 1e3:.0f} ms while pushing {np.linalg.norm(held.args):.3f} N; "
        f"time to zero force on the arm: {(off[0].time_s - held.time_s) * 1e3:.3f} ms after the "
        f"last force command (the firmware's watchdog, {watchdog_s * 1e3:.3f} ms; without it "
        f"the arm would have held the force {gaps[k] * 1e3:.0f} ms)"
    )


def test_a_clients_load_binds_an_arm_and_names_one_that_is_not_there(standin):
    standin.script(f"type=33,{DESCENT}")

    def refused(client) -> None:
        with pytest.raises(ServoError, match="no device 3: the library sees 1"):
            client.load(SPHERE, devices=["forcedimension:3"])

    status = load_and_run("forcedimension:0,max_force=0.5", before=refused)
    assert counters(status)["samples"] >= 100 and counters(status)["faults"] == 0


@pytest.mark.parametrize(
    ("script", "library", "message"),
    [
        (None, "/nonexistent/libdhd.so.3", "HAPTICUT_DHD_LIB=/nonexistent/libdhd.so.3"),
        ("devices=0", None, "no Force Dimension device found"),
        ("open_error=20", None, "another program holds the device"),
        ("reset=1", None, "not initialised (dhdGetStatus: RESET mode"),
    ],
)
def test_no_library_no_device_in_use_or_not_initialised_is_a_clear_device_error(
    standin, script, library, message
):
    check_refused_at_start(standin, "forcedimension", script, library, message)


def test_list_devices_says_where_the_library_is_and_what_it_sees(standin):
    standin.script("devices=2,type=60")
    dhd = listing("forcedimension")
    assert dhd["library_found"] is True and dhd["library"].endswith(DHD_STANDIN)
    assert [d["binding"] for d in dhd["devices"]] == ["forcedimension:0", "forcedimension:1"]
    limits = dhd["devices"][1]["limits"]
    assert dhd["devices"][1]["model"] == "Novint Falcon" and limits["has_force_output"] is True
    assert limits["max_stiffness_N_per_mm_at_rate"] == limits["max_stiffness_N_per_mm"] / 2
    assert dhd["devices"][0]["firmware_watchdog"] is True
    text = run_servo("--list-devices").stdout
    assert DHD_STANDIN in text and "forcedimension:1" in text and "Novint Falcon" in text
    assert "firmware watchdog: yes" in text

    check_listed_without_library(standin, "forcedimension", "/nonexistent/libdhd.so.3")


def test_a_library_without_the_firmware_watchdog_runs_and_says_what_that_leaves(standin):
    """A libdhd before SDK 3.3.2 (the stand-in built without dhdSetWatchdog): the device
    opens and runs; the start log and the listing say a stalled loop leaves the arm its
    last force."""
    standin.name_library(str(built_standin(DHD_STANDIN_NO_WATCHDOG)))
    standin.script("type=33")
    result = run_servo(str(SPHERE), "--device", f"scalpel={BINDING}", "--duration", "0.5")
    assert result.returncode == 0, result.stderr
    warning = "no firmware watchdog: "
    assert warning in result.stderr and "lacks dhdSetWatchdog" in result.stderr
    assert "the arm keeps its last force until the loop runs again" in result.stderr
    assert "dhdSetWatchdog" not in {c.name for c in standin.calls()}
    dhd = listing("forcedimension")
    device = dhd["devices"][0]
    assert device["firmware_watchdog"] is False
    assert "lacks dhdSetWatchdog" in device["firmware_watchdog_warning"]
    assert f"firmware watchdog: {warning}" in run_servo("--list-devices").stdout
