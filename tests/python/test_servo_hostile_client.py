"""A hostile or careless control client cannot hurt the hand (docs/protocol.md, "Limits"):
every message is parsed with bounded depth and size and refused field by field, the files a
client names are read and written only where and as the servo allows, and none of it
crashes the servo, blocks it or reveals a file's content. Each test drives the real binary
over loopback."""

from __future__ import annotations

import contextlib
import json
import os
import socket
import struct
import threading
import time

import pytest
from hapticut.servo_client import PROTOCOL_VERSION, ServoClient, ServoError
from servo_test_support import SPHERE, ServoProcess, connect

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial

LIVE = [str(SPHERE), "--device", "sim:press-slide,speed=20", "--engage"]


def raw_connection(port: int) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port), timeout=10)
    sock.settimeout(10)
    return sock


def send_text(sock: socket.socket, text: bytes) -> None:
    sock.sendall(struct.pack(">I", len(text)) + text)


def read_reply(sock: socket.socket) -> dict:
    def exactly(n: int) -> bytes:
        data = b""
        while len(data) < n:
            chunk = sock.recv(n - len(data))
            assert chunk, "the servo closed the connection"
            data += chunk
        return data

    (length,) = struct.unpack(">I", exactly(4))
    return json.loads(exactly(length))


def ask(sock: socket.socket, text: bytes) -> dict:
    send_text(sock, text)
    return read_reply(sock)


def hello(sock: socket.socket) -> None:
    assert ask(sock, b'{"type":"hello","version":%d}' % PROTOCOL_VERSION)["ok"]


def test_a_deeply_nested_id_is_refused_and_the_servo_runs_on():
    nested = b'{"type":"status","id":' + b"[" * 100_000 + b"]" * 100_000 + b"}"
    with ServoProcess(LIVE) as servo:
        # Before hello, as an attacker would: refused on its length alone, and closed.
        sock = raw_connection(servo.port)
        reply = ask(sock, nested)
        assert not reply["ok"] and "exceeds the limit of 8192 bytes before hello" in reply["error"]
        assert sock.recv(1) == b""
        sock = raw_connection(servo.port)
        hello(sock)
        reply = ask(sock, nested)
        assert not reply["ok"] and "nested deeper than" in reply["error"]
        assert "id" not in reply and len(json.dumps(reply)) < 500
        status = ask(sock, b'{"type":"status"}')
        assert status["state"] == "running" and status["protocol"]["malformed"] == 1
        assert servo.process.poll() is None


def test_loose_values_are_refused_and_name_their_field():
    with ServoProcess(LIVE) as servo:
        sock = raw_connection(servo.port)
        for version in (b"1.5", b"true", b"18446744073709551616", b'"1"'):
            reply = ask(sock, b'{"type":"hello","version":' + version + b"}")
            assert not reply["ok"] and "version: expected an integer" in reply["error"], version
        reply = ask(sock, b'{"type":"hello","version":4294967297}')
        assert "protocol version 4294967297 not supported" in reply["error"]
        hello(sock)
        # The last of two "type"s would have shut the servo down.
        reply = ask(sock, b'{"type":"status","type":"shutdown"}')
        assert not reply["ok"] and "duplicate key" in reply["error"]
        reply = ask(sock, b'{"type":"status"}\x00')
        assert not reply["ok"] and "NUL byte" in reply["error"]
        reply = ask(sock, b'{"type":"subscribe","port":1.5}')
        assert not reply["ok"] and reply["error"].startswith("port: expected an integer")
        for field, value in (
            ("ramp_time_s", "1e308"),
            ("max_force_N", "-1"),
            ("max_torque_N_mm", "0"),
            ("stiffness_N_per_mm", "1e9"),
            ("max_transitions_per_tick", "2.5"),
            ("shading", "1"),
        ):
            text = f'{{"type":"set","{field}":{value}}}'.encode()
            reply = ask(sock, text)
            assert not reply["ok"] and reply["error"].startswith(field + ":"), reply
        status = ask(sock, b'{"type":"status"}')
        assert status["state"] == "running"
        assert status["settings"]["stiffness_N_per_mm"] == pytest.approx(0.1)
        # An id is echoed only when it is small; a long one is refused, not echoed.
        assert ask(sock, b'{"type":"status","id":7}')["id"] == 7
        reply = ask(sock, b'{"type":"status","id":"' + b"x" * 1000 + b'"}')
        assert not reply["ok"] and "id" not in reply and "xxxxx" not in reply["error"]
        reply = ask(sock, b'{"type":"' + b"y" * 1000 + b'"}')
        assert not reply["ok"] and "yyyyy" not in reply["error"]
        assert servo.process.poll() is None


def test_files_that_are_not_regular_are_refused_at_once(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    args = [
        "--device",
        "sim:press-slide,speed=20",
        "--record-dir",
        str(tmp_path),
        "--stop-ramp",
        "0.05",
    ]
    with ServoProcess(args) as servo:
        client = connect(servo)
        for path, kind in (
            (fifo, "a FIFO"),
            ("/dev/zero", "a character device"),
            (tmp_path, "a directory"),
        ):
            with pytest.raises(ServoError, match=f"not a regular file \\({kind}\\)"):
                client.load(path)
        client.load(SPHERE)
        client.start()
        with pytest.raises(ServoError, match="already exists"):
            client.record(fifo)
        assert client.status()["state"] == "running"
        servo.process.terminate()
        assert servo.wait(10) == 0


def test_a_scene_file_over_the_size_limit_is_refused(tmp_path):
    with ServoProcess(["--device", "sim", "--max-scene-bytes", "1000"]) as servo:
        client = connect(servo)
        with pytest.raises(ServoError, match=r"over the limit of .* \(--max-scene-bytes\)"):
            client.load(SPHERE)
        assert client.status()["state"] == "idle"


def test_errors_reveal_nothing_of_a_file(tmp_path):
    secret = tmp_path / "secret.hapticut.json"
    secret.write_text("12345abcdef-secret")
    config = tmp_path / "config.json"
    config.write_text('{"format": "topsecret-format", "key": "value"}')
    with ServoProcess(["--device", "sim"]) as servo:
        client = connect(servo)
        for path in (secret, config):
            with pytest.raises(ServoError) as caught:
                client.load(path)
            message = str(caught.value)
            assert str(path) in message
            assert "12345" not in message and "secret" not in message.replace(str(path), "")
            assert "topsecret" not in message and "json.exception" not in message


def test_recordings_stay_in_the_recording_directory(tmp_path):
    directory = tmp_path / "recordings"
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "kept.rec").write_bytes(b"precious")
    args = [*LIVE, "--record-dir", str(directory)]
    with ServoProcess(args) as servo:
        client = connect(servo)
        refused = {
            str(outside / "new.rec"): "outside the recording directory",
            "../outside/new.rec": '"." or ".."',
            "sub/../../outside/new.rec": '"." or ".."',
            "/etc/hapticut-should-not-exist.rec": "outside the recording directory",
        }
        for path, reason in refused.items():
            with pytest.raises(ServoError, match=reason):
                client.record(path)
        directory.mkdir(exist_ok=True)
        (directory / "link").symlink_to(outside)
        with pytest.raises(ServoError, match="symbolic links are not followed"):
            client.record("link/new.rec")
        (directory / "file.rec").symlink_to(outside / "kept.rec")
        with pytest.raises(ServoError, match="already exists"):
            client.record("file.rec")
        assert sorted(p.name for p in outside.iterdir()) == ["kept.rec"]
        assert (outside / "kept.rec").read_bytes() == b"precious"
        assert not os.path.exists("/etc/hapticut-should-not-exist.rec")

        # Inside: by name or by absolute path; never over an existing file.
        reply = client.record("run.rec")
        assert reply["recording"] == str(directory.resolve() / "run.rec")
        time.sleep(0.2)
        client.stop_recording()
        with pytest.raises(ServoError, match="already exists"):
            client.record(directory / "run.rec")
        assert client.record(directory / "run2.rec")["recording"].endswith("/run2.rec")
        client.stop_recording()
    assert (directory / "run.rec").stat().st_size > 1000


def test_the_token_from_a_file_or_the_environment(tmp_path, monkeypatch):
    token_file = tmp_path / "token"
    token_file.write_text("s3cret-from-file-0123456789\n")
    with ServoProcess([*LIVE, "--token-file", str(token_file)]) as servo:
        with open(f"/proc/{servo.process.pid}/cmdline", "rb") as cmdline:
            assert b"s3cret" not in cmdline.read()
        assert ServoClient(port=servo.port, token="s3cret-from-file-0123456789").hello()["ok"]
        for _ in range(5):
            with pytest.raises(ServoError, match="wrong or missing token"):
                ServoClient(port=servo.port, token="guess").hello()
        # Wrong tries never lock the right token out (test_servo_rightful_client.py).
        assert ServoClient(port=servo.port, token="s3cret-from-file-0123456789").hello()["ok"]
    monkeypatch.setenv("HAPTICUT_SERVO_TOKEN", "s3cret-env-0123456789")
    with ServoProcess(LIVE) as servo:
        with pytest.raises(ServoError, match="wrong or missing token"):
            ServoClient(port=servo.port).hello()
        assert ServoClient(port=servo.port, token="s3cret-env-0123456789").hello()["ok"]


def frame_gaps_while(servo: ServoProcess, action) -> tuple[float, int]:
    """The longest gap between stream frames (s) and the frames received while action() runs."""
    watcher = connect(servo)
    watcher.subscribe(rate_Hz=500.0)
    times: list[float] = []
    done = threading.Event()

    def watch() -> None:
        while not done.is_set():
            if watcher.poll_all():
                times.append(time.monotonic())
            time.sleep(0.0005)

    thread = threading.Thread(target=watch, daemon=True)
    thread.start()
    time.sleep(0.3)
    action()
    time.sleep(0.3)
    done.set()
    thread.join(5)
    watcher.close()
    gaps = [b - a for a, b in zip(times, times[1:], strict=False)]
    return (max(gaps) if gaps else float("inf")), len(times)


def test_a_flooding_client_is_cut_off_and_the_others_are_served():
    with ServoProcess(LIVE) as servo:
        flood = raw_connection(servo.port)
        hello(flood)
        request = b'{"type":"status"}'
        burst = (struct.pack(">I", len(request)) + request) * 50_000

        def pipeline_without_reading() -> None:
            flood.settimeout(0.5)
            with contextlib.suppress(OSError):
                flood.sendall(burst)
            other = raw_connection(servo.port)
            hello(other)  # answered between the flood's messages
            assert ask(other, b'{"type":"status"}')["state"] == "running"
            time.sleep(3.0)  # past the cut-off time of unread replies

        gap_s, frames = frame_gaps_while(servo, pipeline_without_reading)
        print(
            f"\nflood of 50 000 status requests: {frames} frames, longest gap {gap_s * 1e3:.1f} ms"
        )
        client = connect(servo)
        protocol = client.status()["protocol"]
        assert protocol["cut_off_clients"] == 1 and frames > 100
        assert any("cut off" in line for line in servo.stderr_lines)


def test_a_large_message_does_not_hold_up_the_stream():
    with ServoProcess(LIVE) as servo:
        big = raw_connection(servo.port)
        hello(big)
        padding = b"x" * (16 * 1024 * 1024 - 64)
        text = b'{"type":"status","pad":"' + padding + b'"}'

        def send_big() -> None:
            reply = ask(big, text)  # read whole and refused by its field's name
            assert not reply["ok"] and reply["error"].startswith("unknown field 'pad'")
            assert ask(big, b'{"type":"status"}')["state"] == "running"

        gap_s, frames = frame_gaps_while(servo, send_big)
        print(f"\none 16 MiB message: {frames} frames, longest gap {gap_s * 1e3:.1f} ms")
        assert frames > 100
