"""The forcedimension device kind through the real servo binary, with the DHD stand-in
(server/devices/tests/dhd_standin.h, built with the C++ tests) loaded in place of Force
Dimension's library through $HAPTICUT_DHD_LIB: a session clamped, recorded and replayed,
with the sample-to-force latency measured; an error mid-session (force zero in that tick,
the device reopened, the force ramped back); a client's `load` binding an arm; the errors of
a missing library, no device, a device in use and one not initialised; `--list-devices`."""

from __future__ import annotations

import numpy as np
import pytest
from hapticut.servo_client import ServoError
from servo_test_support import SPHERE, independent_scene, run_servo
from standin_support import (
    DHD_STANDIN,
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
BINDING = f"forcedimension:0,max_force={MAX_FORCE_N}"
# Down from 10 mm above the sphere's centre to 10 mm below it over 1000 reads (the SDK's
# frame, m), then held there, pushing.
DESCENT = "from=0:0:0.010,to=0:0:-0.010,reads=1000"


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
    text = run_servo("--list-devices").stdout
    assert DHD_STANDIN in text and "forcedimension:1" in text and "Novint Falcon" in text

    check_listed_without_library(standin, "forcedimension", "/nonexistent/libdhd.so.3")
