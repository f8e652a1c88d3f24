"""The openhaptics device kind through the real servo binary, with the OpenHaptics stand-in
(server/devices/tests/hd_standin.h, built with the C++ tests: libHD's C symbols and its own
scheduler thread at 1 kHz) loaded in place of 3D Systems' library through
$HAPTICUT_OPENHAPTICS_LIB: a session clamped, recorded and replayed bit for bit, with the
sample-to-force latency measured; an HD error mid-session (force zero in that frame, the
device reopened, the force ramped back); the scheduler stalling; the errors of a missing
library, no device, an uncalibrated device and one in use; `--list-devices`."""

from __future__ import annotations

import numpy as np
import pytest
from hapticut.servo_layout import flag_bit
from servo_test_support import independent_scene, read_recording, run_servo
from standin_support import (
    HD_STANDIN,
    Call,
    Standin,
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
BINDING = f"openhaptics:max_force={MAX_FORCE_N}"
# Down from 10 mm above the sphere's centre to 10 mm below it over 1000 frames (OpenHaptics's
# frame, mm: y is up), then held there, pushing.
DESCENT = "from=0:10:0,to=0:-10:0,frames=1000"
FORCE = "hdSetDoublev(FORCE)"
TRANSFORM = "hdGetDoublev(TRANSFORM)"
CONTINUOUS_FORCE = float(0x2604)  # HD_NOMINAL_MAX_CONTINUOUS_FORCE, as the record holds it
FRESH = 0  # DeviceStatus::Fresh, as the recording holds a tick's device status


@pytest.fixture
def standin(monkeypatch, tmp_path) -> Standin:
    return use_standin(
        monkeypatch, tmp_path, HD_STANDIN, "HAPTICUT_OPENHAPTICS_LIB", "HAPTICUT_HD_STANDIN"
    )


def scene_force(call: Call) -> tuple[float, float, float]:
    """A force set in OpenHaptics's axes, in the scene's: scene = (x, -z, y)."""
    x, y, z = call.args
    return (x + 0.0, -z + 0.0, y + 0.0)  # + 0.0: -0.0 compares as 0.0 in a set of tuples


def test_a_session_is_clamped_recorded_replayed_and_its_latency_measured(standin, tmp_path):
    """The stylus drives the blade; each force the callback sets is in a frame, in the
    device's axes, within the clamp, ramped in, and one the servo recorded; the force output
    is enabled only after the limits are read; the recorded proxies equal an offline engine
    run of the recorded poses, and a replay of the recording gives them again bit for bit.
    Prints the sample-to-force latency the callback measured (not asserted)."""
    standin.script(DESCENT)
    scene = independent_scene(tmp_path / "sphere.hapticut.json")
    record = tmp_path / "hd.rec"
    status = run_session(scene, record, BINDING, lambda s: counters(s).get("samples", 0) > 2000)
    blade = status["blades"][0]
    assert blade["kind"] == "openhaptics" and blade["passivity"] is True
    assert blade["device_error"] == ""
    found = counters(status)
    assert found["faults"] == 0 and found["forces_written"] > 2000
    print_sample_to_force("OpenHaptics", found)

    calls = standin.calls()
    limits = index_of(calls, "hdGetDoublev", a=CONTINUOUS_FORCE)
    enable = index_of(calls, "hdEnable")
    assert index_of(calls, "hdInitDevice") < limits < enable < index_of(calls, "hdStartScheduler")
    forces = [c for c in calls if c.name == FORCE]
    assert all(c.in_frame and c.result == 0 for c in forces), "a force set outside a frame"
    assert forces[-1].args == (0.0, 0.0, 0.0)
    tail = [
        c.name for c in calls if c.name in ("hdUnschedule", "hdStopScheduler", "hdDisableDevice")
    ]
    assert tail[-3:] == ["hdUnschedule", "hdStopScheduler", "hdDisableDevice"]
    magnitudes = np.array([np.linalg.norm(c.args) for c in forces])
    assert 0.1 < magnitudes.max() <= MAX_FORCE_N + 1e-9

    block = read_recording(record).blade("scalpel")["block"]
    assert block["ramp"][np.argmax(np.linalg.norm(block["force_N"], axis=1) > 0)] < 1.0
    pushed = [scene_force(c) for c in forces if any(c.args)]
    check_session_recorded_and_replayed(scene, record, pushed, MAX_FORCE_N)


def test_an_hd_error_mid_session_zeroes_the_force_in_that_frame_and_ramps_back(standin, tmp_path):
    """A failed read of the transform while pushing: a zero force in that same frame, the
    device lost, nothing pushed until maintain() reopened it (limits read before the force
    output is enabled again), then the force ramped back in."""
    standin.script(f"{DESCENT},fail_frame_at=1500,fail_count=1")
    scene = independent_scene(tmp_path / "sphere.hapticut.json")
    record = tmp_path / "fault.rec"

    def reopened_and_pushing(status: dict) -> bool:
        return counters(status).get("reconnects", 0) >= 1 and counters(status)["samples"] > 2500

    status = run_session(scene, record, BINDING, reopened_and_pushing)
    assert counters(status)["faults"] == 1 and counters(status)["reconnects"] == 1
    assert status["blades"][0]["events"]["device_lost"] >= 1

    calls = standin.calls()
    failed = next(i for i, c in enumerate(calls) if c.name == TRANSFORM and c.result != 0)
    zero = index_of(calls, FORCE, failed)
    assert calls[zero].frame == calls[failed].frame and calls[zero].args == (0.0, 0.0, 0.0)
    print(
        "\ntime to zero force after an HD error in the callback in the servo: 0 frames, "
        f"{(calls[zero].time_s - calls[failed].time_s) * 1e6:.1f} us"
    )
    pushing = [c for c in calls[:failed] if c.name == FORCE][-1]
    assert np.linalg.norm(pushing.args) > 0.05, "not pushing at the fault: proves nothing"
    stopped = index_of(calls, "hdStopScheduler", zero)
    reopened = index_of(calls, "hdInitDevice", stopped)
    limits = index_of(calls, "hdGetDoublev", reopened, a=CONTINUOUS_FORCE)
    enabled = index_of(calls, "hdEnable", limits)
    assert stopped < index_of(calls, "hdDisableDevice", stopped) < reopened < limits < enabled
    between = [c for c in calls[zero + 1 : enabled] if c.name == FORCE]
    assert between == [], "the ended callback still set forces"
    check_lost_then_ramped_back(record)


def test_a_stalled_scheduler_trips_the_servos_watchdog_and_the_force_ramps_back(standin, tmp_path):
    """The device's scheduler stops for 300 ms while pushing: the loop sees no new sample,
    its watchdog zeroes the force, and once frames come again the force ramps back."""
    standin.script(f"{DESCENT},stall_at=1500,stall_ms=300")
    scene = independent_scene(tmp_path / "sphere.hapticut.json")
    record = tmp_path / "stall.rec"
    status = run_session(scene, record, BINDING, lambda s: counters(s).get("frames", 0) > 2500)
    assert counters(status)["faults"] == 0
    block = read_recording(record).blade("scalpel")["block"]
    force = np.linalg.norm(block["force_N"], axis=1)
    tripped = np.nonzero(block["events"] & flag_bit("watchdog"))[0]
    assert len(tripped) >= 1
    k = int(tripped[0])
    assert force[k] == 0.0 and force[k - 120 : k - 100].max() > 0.05
    assert force[k:].max() > 0.05, "the force never came back"
    calls = standin.calls()
    stalled = [c for c in calls if c.name == FORCE and c.frame == 1500]
    assert stalled and all(c.in_frame for c in stalled)
    # No frame runs while the scheduler stalls: the arm holds the last frame's force
    # through it; the first frame after it sets the loop's newest force.
    held = next(c for c in calls if c.name == FORCE and c.frame == 1499)
    last_fresh = int(np.nonzero(block["device_status"][:k] == FRESH)[0][-1])
    print(
        f"\nscheduler stalled {(stalled[0].time_s - held.time_s) * 1e3:.0f} ms, the arm holding "
        f"{np.linalg.norm(held.args):.3f} N; the servo's watchdog zeroed its force "
        f"{k - last_fresh} ticks after the last sample; the first frame after the stall set "
        f"{np.linalg.norm(stalled[0].args):.3f} N"
    )


def test_a_clients_load_binds_the_device(standin):
    standin.script(DESCENT)
    status = load_and_run("openhaptics:max_force=0.5")
    assert counters(status)["samples"] >= 100 and counters(status)["faults"] == 0


@pytest.mark.parametrize(
    ("script", "library", "message"),
    [
        (None, "/nonexistent/libHD.so.3.4", "HAPTICUT_OPENHAPTICS_LIB=/nonexistent/libHD.so.3.4"),
        ("devices=0", None, "hdInitDevice failed: Communication error"),
        ("init_error=0x301", None, "another program (or another servo) holds the device"),
        ("calibration=manual", None, "not calibrated"),
    ],
)
def test_no_library_no_device_uncalibrated_or_in_use_is_a_clear_device_error(
    standin, script, library, message
):
    check_refused_at_start(standin, "openhaptics", script, library, message)


def test_list_devices_says_where_the_library_is_and_the_devices_limits(standin):
    standin.script("continuous=0.88,stiffness=1.2")
    hd = listing("openhaptics")
    assert hd["library_found"] is True and hd["library"].endswith(HD_STANDIN)
    assert [d["binding"] for d in hd["devices"]] == ["openhaptics"]
    limits = hd["devices"][0]["limits"]
    assert limits["has_force_output"] is True and limits["max_force_N"] == 0.88
    assert limits["max_stiffness_N_per_mm_at_rate"] == 0.6
    text = run_servo("--list-devices").stdout
    assert HD_STANDIN in text and "max continuous force 0.88 N" in text

    check_listed_without_library(standin, "openhaptics", "/nonexistent/libHD.so")
