"""The real devices through the real servo binary over loopback: the example UDP bridge
(examples/bridge_example.py) as a child process driving `--device scalpel=bridge:...`,
the bridge going silent and coming back, a bridge sending garbage, the engage request bit,
`--list-devices` through the real hidapi, and bad hid and bridge bindings."""

from __future__ import annotations

import importlib.util
import json
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from hapticut.servo_layout import flag_bit
from servo_test_support import (
    EXAMPLES,
    SPHERE,
    ServoProcess,
    connect,
    independent_scene,
    offline_check,
    read_recording,
    run_servo,
)

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial

BRIDGE = EXAMPLES / "bridge_example.py"
# The test profiles (example-force-device.json: a stiffness limit of its own).
TEST_PROFILE_DIR = Path(__file__).resolve().parents[2] / "server" / "devices" / "tests" / "data"
EXIT_DEVICE = 4  # docs/servo.md


def load_bridge_module():
    """The example bridge's datagram layouts (one definition: the example's)."""
    spec = importlib.util.spec_from_file_location("bridge_example", BRIDGE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def hid_section(listing: str) -> list[str]:
    """The HID table of `--list-devices` (the Force Dimension section follows a blank line)."""
    return listing.split("\n\n")[0].splitlines()


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_bridge(port: int, *args: str) -> subprocess.Popen:
    command = [sys.executable, str(BRIDGE), "--servo", f"127.0.0.1:{port}", "--summary", *args]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def bridge_summary(bridge: subprocess.Popen, timeout_s: float = 30.0) -> dict:
    out, err = bridge.communicate(timeout=timeout_s)
    assert bridge.returncode == 0, err
    return json.loads(out.strip().splitlines()[-1])


def servo_args(port: int, record=None, device_options: str = "", scene=SPHERE) -> list[str]:
    args = [str(scene), "--device", f"scalpel=bridge:port={port}{device_options}"]
    args += ["--engage", "--ramp", "0.05"]
    if record is not None:
        args += ["--record", str(record)]
    return args


def collect_frames(client, bridge: subprocess.Popen) -> list:
    frames = []
    while bridge.poll() is None:
        frames += client.poll_all()
        time.sleep(0.01)
    return frames + client.poll_all()


def test_bridge_drives_the_servo(tmp_path):
    """Frames arrive with the bridge's poses, the bridge feels the force, clamped to the
    bridge's limits, and the recorded proxies equal an offline engine run of those poses."""
    port = free_udp_port()
    record = tmp_path / "bridge.rec"
    # The hand starts with the edge in the sphere: a rigid blade there has no pose, no force.
    scene = independent_scene(tmp_path / "sphere.hapticut.json")
    with ServoProcess(servo_args(port, record, ",max_force=0.5", scene)) as servo:
        client = connect(servo, ["scalpel"])
        client.subscribe(rate_Hz=200)
        bridge = start_bridge(port, "--duration", "2.0")
        frames = collect_frames(client, bridge)
        summary = bridge_summary(bridge)
        status = client.status()
        client.close()
        assert servo.stop() == 0
    blade = status["blades"][0]
    assert blade["kind"] == "bridge" and blade["passivity"] is True
    assert blade["device_error"] == ""
    counters = blade["device_counters"]
    assert counters["poses"] > 500 and counters["garbage"] == 0
    assert counters["forces_sent"] > 500

    assert len(frames) > 100, f"only {len(frames)} frames"
    fresh = [f for f in frames if int(f.blades["scalpel"]["block"]["device_status"]) == 0]
    assert len(fresh) > 100
    z = np.array([f.blades["scalpel"]["block"]["pose"][2] for f in fresh])
    assert z.max() > 5.0 and z.min() < -5.0  # the scripted hand's descent, 10 to -10 mm

    assert summary["forces_received"] > 500
    assert 0.1 < summary["max_force_N"] <= 0.5 + 1e-9  # felt, and within the bridge's limit

    recording = read_recording(record)
    block = recording.blade("scalpel")["block"]
    rendered = np.linalg.norm(block["force_N"], axis=1)
    engine = np.linalg.norm(block["engine_force_N"], axis=1)
    assert rendered.max() <= 0.5 + 1e-9
    assert engine.max() > 0.5, "the engine never asked for more than the clamp: proves nothing"
    assert np.any(block["safety_flags"] & flag_bit("force_clamped"))
    assert offline_check(scene, recording, "scalpel") > 500


def test_bridge_silent_is_lost_then_ramps_back(tmp_path):
    """A bridge that stops sending is a lost device: force zero in the tick it is declared
    lost, reported; a bridge that speaks again (a restarted one) is taken back, ramped in."""
    port = free_udp_port()
    record = tmp_path / "silent.rec"
    # The hand starts with the edge in the sphere: a rigid blade there has no pose, no force.
    scene = independent_scene(tmp_path / "sphere.hapticut.json")
    with ServoProcess(servo_args(port, record, ",timeout_ms=100", scene)) as servo:
        client = connect(servo, ["scalpel"])
        first = start_bridge(port, "--duration", "1.6", "--silent-after", "0.9")
        first_summary = bridge_summary(first)
        lost_status = client.status()["blades"][0]
        second = start_bridge(port, "--duration", "1.5")
        second_summary = bridge_summary(second)
        back_status = client.status()["blades"][0]
        client.close()
        assert servo.stop() == 0
    assert lost_status["device_status"] == "lost"
    assert lost_status["force_N"] == [0.0, 0.0, 0.0]
    assert "device_lost" in lost_status["flags"]
    assert back_status["events"]["device_lost"] >= 1
    assert any("fault device_lost" in line for line in servo.stderr_lines)
    assert first_summary["forces_received"] > 100 and second_summary["forces_received"] > 100

    recording = read_recording(record)
    block = recording.blade("scalpel")["block"]
    force = np.linalg.norm(block["force_N"], axis=1)
    lost = np.nonzero(block["events"] & flag_bit("device_lost"))[0]
    assert len(lost) >= 1
    k = int(lost[0])
    assert force[k - 1] > 0.05, "no force before the silence: the test would prove nothing"
    assert force[k] == 0.0
    status = block["device_status"]
    back = k + int(np.argmax(status[k:] != 2))
    assert back > k and np.all(force[k:back] == 0.0)
    # Ramped back in from zero after the fault, and pushing again.
    assert block["ramp"][back] < 0.2
    assert force[back:].max() > 0.05
    assert second_summary["max_force_N"] > 0.05


def test_bridge_garbage_is_refused_counted_and_reported():
    port = free_udp_port()
    with ServoProcess(servo_args(port)) as servo:
        client = connect(servo, ["scalpel"])
        client.subscribe(rate_Hz=100)
        bridge = start_bridge(port, "--duration", "1.5", "--garbage-every", "3")
        frames = collect_frames(client, bridge)
        summary = bridge_summary(bridge)
        status = client.status()
        client.close()
        assert servo.process.poll() is None, "the servo died"
        assert servo.stop() == 0
    assert summary["garbage_sent"] > 100
    counters = status["blades"][0]["device_counters"]
    assert counters["garbage"] == summary["garbage_sent"]
    refused = {k: v for k, v in counters.items() if k.startswith("refused_")}
    assert sum(refused.values()) == counters["garbage"]
    for reason in ("wrong_length", "bad_magic", "bad_version", "not_finite"):
        assert refused[f"refused_{reason}"] > 0, reason
    assert counters["poses"] > 0 and status["state"] == "running"
    # No garbage reached the engine: no non-finite pose, and frames kept coming.
    assert status["blades"][0]["events"].get("non_finite_pose", 0) == 0
    assert len(frames) > 50


def test_engage_request_bit_toggles_engage():
    """Bit 31 of the device's buttons (a puck's engage button, or a bridge) sets the servo's
    engage state at each change."""
    bridge = load_bridge_module()
    port = free_udp_port()
    args = [str(SPHERE), "--device", f"scalpel=bridge:port={port}", "--ramp", "0.05"]
    engage_bit = 1 << 31
    with ServoProcess(args) as servo:
        client = connect(servo, ["scalpel"])
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            sequence = 0

            def send_for(seconds: float, buttons: int) -> None:
                nonlocal sequence
                end = time.monotonic() + seconds
                while time.monotonic() < end:
                    sequence += 1
                    pose = bridge.POSE.pack(
                        bridge.MAGIC, bridge.VERSION, bridge.POSE_KIND, sequence,
                        time.monotonic(), 0.0, 0.0, 30.0, 1.0, 0.0, 0.0, 0.0, buttons, 0, 0,
                    )  # fmt: skip
                    sock.sendto(pose, ("127.0.0.1", port))
                    time.sleep(0.002)

            send_for(0.3, 0)
            assert client.status()["engaged"] is False
            send_for(0.3, engage_bit | 1)
            assert client.status()["engaged"] is True
            send_for(0.3, 0)
            assert client.status()["engaged"] is False
            client.engage(True)  # a control message still engages while the bit stays off
            send_for(0.2, 0)
            assert client.status()["engaged"] is True
        client.close()
        assert servo.stop() == 0


def test_list_devices_through_hidapi():
    result = run_servo("--list-devices")
    assert result.returncode == 0, result.stderr
    lines = hid_section(result.stdout)
    # No HID device on a CI machine is a valid result and prints as such.
    if lines == ["no HID devices found"]:
        return
    assert lines[0].split()[:3] == ["path", "vendor:product", "usage"]
    assert len(lines) > 1


def test_list_devices_json_lists_what_the_table_lists_and_every_profile(tmp_path):
    result = run_servo("--list-devices", "--json")
    assert result.returncode == 0, result.stderr
    listing = json.loads(result.stdout)
    assert listing["version"] == 1
    table = hid_section(run_servo("--list-devices").stdout)
    found = [] if table == ["no HID devices found"] else table[1:]
    assert [d["path"] for d in listing["devices"]] == [line.split()[0] for line in found]
    for device in listing["devices"]:
        assert device["binding"] == (f"hid:{device['profile']}" if device["profile"] else None)
    files = {p.stem for p in Path(listing["profile_directory"]).glob("*.json")}
    assert files and {p["name"] for p in listing["profiles"]} == files
    assert all(p["binding"] == f"hid:{p['name']}" for p in listing["profiles"])
    kinds = {k["kind"]: k for k in listing["kinds"]}
    assert set(kinds) == {"sim", "viewport", "bridge"}
    assert kinds["bridge"]["binding"].startswith("bridge:port=")
    assert kinds["sim"]["limits"]["has_force_output"] is True
    assert kinds["viewport"]["limits"]["has_force_output"] is False
    assert run_servo("--json").returncode == 2
    missing = run_servo("--list-devices", "--json", "--profiles", str(tmp_path / "none"))
    assert missing.returncode == EXIT_DEVICE and missing.stdout == ""


def test_list_devices_json_gives_each_stiffness_limit_at_the_rate():
    """The servo's own stiffness limit at a loop rate (stiffness_limit, server/safety.h), for
    the add-on to compare against: a quarter of the 1 kHz limit at 250 Hz, the stated one at
    or above 1 kHz. The shipped profiles state none: the test profile with force output does."""
    profiles = str(TEST_PROFILE_DIR)
    stated = json.loads(run_servo("--list-devices", "--json", "--profiles", profiles).stdout)
    assert stated["rate_Hz"] == 1000.0
    slow = run_servo("--list-devices", "--json", "--rate", "250", "--profiles", profiles)
    assert slow.returncode == 0, slow.stderr
    slow = json.loads(slow.stdout)
    assert slow["rate_Hz"] == 250.0
    fast = json.loads(run_servo("--list-devices", "--json", "--rate", "4000").stdout)
    entries = {
        "profile": (stated["profiles"][0], slow["profiles"][0], None),
        "bridge": (*(next(k for k in x["kinds"] if k["kind"] == "bridge") for x in (stated, slow)),
                   next(k for k in fast["kinds"] if k["kind"] == "bridge")),
    }  # fmt: skip
    for name, (at_1k, at_250, at_4k) in entries.items():
        limit = at_1k["limits"]["max_stiffness_N_per_mm"]
        assert limit > 0, name
        assert at_1k["limits"]["max_stiffness_N_per_mm_at_rate"] == limit, name
        # The rate the stated limit holds for, in every listing whatever its rate.
        for listing in (at_1k, at_250, at_4k):
            if listing is not None:
                assert listing["limits"]["max_stiffness_stated_rate_Hz"] == 1000.0, name
        assert at_250["limits"]["max_stiffness_N_per_mm"] == limit, name
        assert at_250["limits"]["max_stiffness_N_per_mm_at_rate"] == pytest.approx(limit / 4)
        if at_4k is not None:
            assert at_4k["limits"]["max_stiffness_N_per_mm_at_rate"] == limit, name
    # None known stays none at any rate.
    sim = next(k for k in slow["kinds"] if k["kind"] == "sim")["limits"]
    assert sim["max_stiffness_N_per_mm"] == 0 and sim["max_stiffness_N_per_mm_at_rate"] == 0
    profile = slow["profiles"][0]
    limits = profile["limits"]
    print(
        f"\n{profile['name']}: {limits['max_stiffness_N_per_mm']:g} N/mm at 1 kHz, "
        f"{limits['max_stiffness_N_per_mm_at_rate']:g} N/mm at 250 Hz"
    )


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--rate", "0"], "--rate: 1 to 10000 Hz"),
        (["--rate", "-250"], "--rate: 1 to 10000 Hz"),
        (["--rate", "20000"], "--rate: 1 to 10000 Hz"),
        (["--rate", "nan"], "--rate: 'nan' is not a number"),
        (["--rate", "inf"], "--rate: 'inf' is not a number"),
        (["--rate", "fast"], "--rate: 'fast' is not a number"),
        (["--rate", ""], "--rate: '' is not a number"),
        (["--rate"], "--rate: needs a value"),
    ],
)
def test_list_devices_json_bad_rate_is_a_usage_error(args, message):
    result = run_servo("--list-devices", "--json", *args)
    assert result.returncode == 2 and result.stdout == ""
    assert message in result.stderr, result.stderr


def test_list_devices_rate_goes_with_json():
    result = run_servo("--list-devices", "--rate", "250")
    assert result.returncode == 2 and "goes with --json" in result.stderr, result.stderr
    assert "max_stiffness_N_per_mm_at_rate" in run_servo("--help").stdout


def test_list_devices_documented_and_profiles_dir_checked(tmp_path):
    usage = run_servo("--help").stdout
    for text in ("--list-devices", "--profiles DIR", "--no-passivity", "hid:", "bridge:"):
        assert text in usage, text
    missing = tmp_path / "no-profiles"
    result = run_servo("--list-devices", "--profiles", str(missing))
    assert result.returncode == EXIT_DEVICE
    assert str(missing) in result.stderr


@pytest.mark.parametrize(
    ("device", "message"),
    [
        ("hid:no-such-profile", "no profile named 'no-such-profile'"),
        ("hid:spacenavigator,mode=sideways", "mode=sideways"),
        ("hid:spacenavigator,colour=red", "unknown option 'colour'"),
        ("hid:profile=/nonexistent/x.json", "/nonexistent/x.json"),
        ("hid:spacenavigator", "no device matches profile 'spacenavigator'"),
        ("bridge:port=99999", "port"),
        ("bridge:stray", "'stray' is not key=value"),
    ],
)
def test_bad_device_binding_exits_with_device_code(device, message):
    result = run_servo(str(SPHERE), "--device", f"scalpel={device}", "--duration", "0.2")
    assert result.returncode == EXIT_DEVICE, result.stderr
    assert f"scalpel={device}" in result.stderr  # names the device
    assert message in result.stderr
