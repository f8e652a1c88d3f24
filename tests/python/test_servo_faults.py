"""Faults at the device and on the wire: the servo survives, the force is zero within one
tick of the fault, the fault is reported, and the recording holds every tick before it."""

from __future__ import annotations

import re
import signal
import socket
import struct
import subprocess
import sys
import time

import numpy as np
import pytest
from hapticut.servo_client import ServoError
from hapticut.servo_layout import FAULT_MASK, flag_bit
from servo_test_support import (
    SPHERE,
    ServoProcess,
    bake,
    connect,
    offline_check,
    read_recording,
    run_servo,
)

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial

LIVE = [str(SPHERE), "--device", "sim:press-slide,speed=20", "--engage"]


def first_fault(recording, blade="scalpel", flag="device_lost") -> int:
    events = recording.blade(blade)["block"]["events"]
    hits = np.nonzero(events & flag_bit(flag))[0]
    assert len(hits), f"no {flag} event recorded"
    return int(hits[0])


def assert_faulted_at(recording, k: int, blade="scalpel"):
    block = recording.blade(blade)["block"]
    force = np.linalg.norm(block["force_N"], axis=1)
    assert force[k - 1] > 0.05, "no force before the fault: the test would prove nothing"
    assert force[k] == 0.0, "force not zero in the tick of the fault"
    assert np.array_equal(recording.ticks["tick"][: k + 1], np.arange(k + 1))
    assert int(recording.ticks["dropped_records"][k]) == 0


def test_sim_device_fails_mid_stroke(tmp_path):
    record = tmp_path / "fail.rec"
    stats = bake(SPHERE, record, "scalpel=sim:press-slide,fail_at_s=0.3", extra=("--ramp", "0.05"))
    recording = read_recording(record)
    k = first_fault(recording)
    assert_faulted_at(recording, k)
    block = recording.blade("scalpel")["block"]
    assert np.all(block["force_N"][k:] == 0.0)  # lost for good: never pushes again
    assert np.all(block["device_status"][k:] == 2)
    assert np.all(block["safety_flags"][k:] & FAULT_MASK)
    blade = stats["blades"][0]
    assert blade["faults"] == 1 and blade["events"]["device_lost"] == 1
    assert offline_check(SPHERE, recording, "scalpel") == k


def test_sim_device_recovers_after_failing(tmp_path):
    record = tmp_path / "recover.rec"
    device = "scalpel=sim:press-slide,fail_at_s=0.25,recover_at_s=0.3"
    bake(SPHERE, record, device, extra=("--ramp", "0.05"))
    recording = read_recording(record)
    k = first_fault(recording)
    assert_faulted_at(recording, k)
    force = np.linalg.norm(recording.blade("scalpel")["block"]["force_N"], axis=1)
    back = k + np.nonzero(force[k:] > 0)[0][0]
    assert force[back] < force[k - 1]  # ramps back up from zero, no jump


def test_sim_device_sends_nan(tmp_path):
    record = tmp_path / "nan.rec"
    result = run_servo(
        str(SPHERE),
        "--as-fast-as-possible",
        "--exit-when-done",
        "--engage",
        "--ramp",
        "0.05",
        "--device",
        "sim:press-slide,nan_at_s=0.25,nan_ticks=3",
        "--record",
        str(record),
    )
    assert result.returncode == 0
    assert "fault non_finite_pose" in result.stderr
    recording = read_recording(record)
    k = first_fault(recording, flag="non_finite_pose")
    assert_faulted_at(recording, k)
    block = recording.blade("scalpel")["block"]
    assert np.all(block["force_N"][k : k + 3] == 0.0) and np.all(block["step_kind"][k : k + 3] == 0)
    assert np.all(np.isfinite(recording.blade("scalpel")["q"]))  # NaN never reaches a proxy
    assert np.linalg.norm(block["force_N"][k + 60]) > 0.05  # and the run went on, ramped up


def test_viewport_device_going_silent(tmp_path):
    record = tmp_path / "viewport.rec"
    args = [str(SPHERE), "--device", "viewport", "--watchdog-ms", "150", "--record", str(record)]
    with ServoProcess(args) as servo:
        client = connect(servo)
        for i in range(30):  # ~100 Hz, pressing into the sphere
            client.send_pose("scalpel", [0, 0, 40 - i * 0.5, 1, 0, 0, 0])
            time.sleep(0.01)
        time.sleep(0.5)  # silent
        status = client.status()
        blade = status["blades"][0]
        assert blade["device_status"] == "lost" and "device_lost" in blade["flags"]
        assert blade["faults"] == 1
        client.send_pose("scalpel", [0, 0, 20, 1, 0, 0, 0])  # back
        time.sleep(0.02)
        assert client.status()["blades"][0]["device_status"] == "fresh"
        client.stop()
    assert any("fault device_lost" in line for line in servo.stderr_lines)
    recording = read_recording(record)
    k = first_fault(recording)
    block = recording.blade("scalpel")["block"]
    assert np.all(block["step_kind"][k:][block["device_status"][k:] == 2] == 0)
    assert np.all(block["engine_force_N"][k][...] == 0.0)
    assert np.linalg.norm(block["engine_force_N"][k - 1]) > 0  # it was cutting
    assert np.all(block["force_N"] == 0.0)  # a viewport renders nothing, ever
    assert np.array_equal(recording.ticks["tick"][: k + 1], np.arange(k + 1))
    assert offline_check(SPHERE, recording, "scalpel") > 0


def test_client_killed_mid_stream():
    with ServoProcess(LIVE) as servo:
        child = subprocess.Popen(
            [
                sys.executable,
                "-c",
                (
                    "import time, sys; from hapticut.servo_client import ServoClient\n"
                    f"c = ServoClient(port={servo.port}); c.hello(); c.subscribe(rate_Hz=500)\n"
                    "print('subscribed', flush=True)\n"
                    "while True: c.poll(); time.sleep(0.001)\n"
                ),
            ],
            stdout=subprocess.PIPE,
            text=True,
        )
        assert child.stdout.readline().strip() == "subscribed"
        time.sleep(0.2)
        child.send_signal(signal.SIGKILL)
        child.wait()
        client = connect(servo)
        ticks = client.status()["ticks"]
        time.sleep(0.2)
        status = client.status()
        assert status["state"] == "running" and status["ticks"] > ticks + 100
        assert status["protocol"]["subscribers"] == 0  # its subscription went with it
        assert status["protocol"]["frames_sent"] > 20


def raw_connection(port: int) -> socket.socket:
    return socket.create_connection(("127.0.0.1", port), timeout=5)


def read_reply(sock: socket.socket) -> dict:
    import json

    header = sock.recv(4, socket.MSG_WAITALL)
    (length,) = struct.unpack(">I", header)
    return json.loads(sock.recv(length, socket.MSG_WAITALL))


def test_garbage_bytes_wrong_version_and_huge_prefix():
    with ServoProcess(LIVE) as servo:
        client = connect(servo)
        # Framed garbage: an error, the connection stays usable.
        client.send_raw(struct.pack(">I", 9) + b"\xffnot json")
        reply = client.receive_message()
        assert not reply["ok"] and "malformed JSON" in reply["error"]
        client.send_raw(struct.pack(">I", 2) + b"[]")
        assert "expected an object" in client.receive_message()["error"]
        with pytest.raises(ServoError, match="unknown message type"):
            client.request("fly")
        with pytest.raises(ServoError, match="unknown parameter"):
            client.set_parameters(warp=9)
        assert client.status()["state"] == "running"

        # Wrong protocol version, then anything before a good hello.
        other = connect_without_hello(servo.port)
        with pytest.raises(ServoError, match="protocol version 99 not supported"):
            other.request("hello", version=99)
        with pytest.raises(ServoError, match='before "hello"'):
            other.status()
        other.hello()
        assert other.status()["state"] == "running"

        # A 1 GB length prefix: refused before buffering, connection closed.
        sock = raw_connection(servo.port)
        sock.sendall(struct.pack(">I", 1 << 30) + b"x" * 1000)
        reply = read_reply(sock)
        assert not reply["ok"] and "exceeds the limit" in reply["error"]
        assert sock.recv(1) == b""
        # Unframed garbage (an HTTP request): its first 4 bytes are a huge length.
        sock = raw_connection(servo.port)
        sock.sendall(b"GET / HTTP/1.1\r\nHost: x\r\n\r\n")
        assert not read_reply(sock)["ok"]

        status = client.status()
        protocol = status["protocol"]
        assert status["state"] == "running"
        assert protocol["malformed"] >= 2 and protocol["oversized"] == 2
        assert protocol["unauthenticated"] == 1 and protocol["out_of_order"] == 1


def connect_without_hello(port: int):
    from hapticut.servo_client import ServoClient

    return ServoClient(port=port).connect()


def test_udp_flood_at_the_stream_port():
    with ServoProcess(LIVE) as servo:
        client = connect(servo, ["scalpel"])
        target = ("127.0.0.1", client.subscribe(rate_Hz=200)["stream_source_port"])
        flood = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        junk = b"\x00" * 1400
        end = time.monotonic() + 0.5
        sent = 0
        while time.monotonic() < end:
            for _ in range(200):
                flood.sendto(junk, target)
                sent += 1
        client.poll_all()
        time.sleep(0.2)
        frames = client.poll_all()
        assert len(frames) >= 20  # the stream goes on
        status = client.status()
        assert status["state"] == "running"
        assert status["protocol"]["stray_datagrams"] > 0
        assert sent > 1000


def test_missing_and_invalid_scene_files(tmp_path):
    result = run_servo(str(tmp_path / "nope.hapticut.json"), "--device", "sim")
    assert result.returncode == 3
    assert "nope.hapticut.json" in result.stderr and "(file)" in result.stderr
    bad = tmp_path / "bad.hapticut.json"
    bad.write_text('{"format": "hapticut.scene", "version": 1, "mesh": 3}')
    result = run_servo(str(bad), "--device", "sim")
    assert result.returncode == 3 and "bad.hapticut.json" in result.stderr
    assert re.search(r"json': /\w+", result.stderr), result.stderr  # names the field
    # Over the control channel: an error reply, the servo stays up.
    with ServoProcess([]) as servo:
        client = connect(servo)
        with pytest.raises(ServoError, match="cannot open|No such file|\\(file\\)"):
            client.load(path=str(tmp_path / "nope.hapticut.json"), devices=["sim"])
        with pytest.raises(ServoError, match="scene: "):
            client.load(path=str(bad), devices=["sim"])
        with pytest.raises(ServoError, match="no scene loaded"):
            client.start()
        assert client.status()["state"] == "idle"
        reply = client.load(path=str(SPHERE), devices=["sim"])
        assert reply["blades"][0]["name"] == "scalpel"


def test_bad_device_bindings_are_named():
    cases = [
        (["--device", "warp:9"], "unknown device kind 'warp'"),
        (["--device", "sim:press,mass=3"], "unknown option 'mass'"),
        (["--device", "sim:press,speed=fast"], "speed='fast' is not a finite number"),
        (["--device", "knife=sim"], "no blade 'knife'"),
        ([], "has no device"),
    ]
    for args, message in cases:
        result = run_servo(str(SPHERE), *args)
        assert result.returncode == 4, (args, result.stderr)
        assert message in result.stderr, (args, result.stderr)


def test_sigterm_ramps_down_and_closes_the_recording(tmp_path):
    record = tmp_path / "term.rec"
    args = [*LIVE, "--record", str(record), "--ramp", "0.05", "--stop-ramp", "0.05"]
    servo = ServoProcess(args, control=False).start()
    time.sleep(1.5)  # pressing into the sphere by now
    assert servo.stop() == 0
    stats = servo.stats()
    assert stats is not None and stats["recording"]["written"] == stats["ticks"]
    recording = read_recording(record)
    assert recording.truncated_bytes == 0 and len(recording) == stats["ticks"]
    block = recording.blade("scalpel")["block"]
    force = np.linalg.norm(block["force_N"], axis=1)
    stopping = np.nonzero(block["safety_flags"] & flag_bit("stopping"))[0]
    assert len(stopping) >= 10 and force[stopping[0] - 1] > 0.05
    # The stop ramp falls monotonically to zero and bounds the force: ramp x the safety's
    # 5 N clamp (the engine's force may still grow while the device presses on).
    ramp = block["ramp"][stopping]
    assert np.all(np.diff(ramp) <= 1e-12) and ramp[-1] == 0.0
    assert np.all(force[stopping] <= ramp * 5.0 + 1e-9)
    assert force[-1] == 0.0


def test_token_and_listen_rules():
    result = run_servo(str(SPHERE), "--device", "sim", "--control", "0", "--listen", "0.0.0.0")
    assert result.returncode == 5 and "needs --token" in result.stderr
    with ServoProcess([*LIVE, "--token", "s3cret-long-enough-0123"]) as servo:
        from hapticut.servo_client import ServoClient

        with pytest.raises(ServoError, match="wrong or missing token"):
            ServoClient(port=servo.port).hello()
        good = ServoClient(port=servo.port, token="s3cret-long-enough-0123")
        assert good.hello()["ok"]
