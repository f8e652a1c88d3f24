"""The rightful client always gets in (docs/protocol.md, "Security"): whatever other local
processes do to the control port (wrong tokens at any rate, silent or byte-a-second
connections, hundreds of them, every client slot held), a client with the right token, or
any client when none is required, is answered within 1 s. Each attack runs for a few seconds
against the real binary over loopback; the figures are printed."""

from __future__ import annotations

import contextlib
import json
import socket
import struct
import threading
import time

from hapticut.servo_client import PROTOCOL_VERSION
from servo_test_support import SPHERE, ServoProcess, run_servo

LIVE = [str(SPHERE), "--device", "sim:press-slide,speed=20", "--engage"]
TOKEN = "rightful-token-0123456789abcdef"
ANSWER_WITHIN_S = 1.0


def hello_text(token: str | None) -> bytes:
    message = {"type": "hello", "version": PROTOCOL_VERSION}
    if token is not None:
        message["token"] = token
    text = json.dumps(message).encode()
    return struct.pack(">I", len(text)) + text


def read_reply(sock: socket.socket) -> dict | None:
    """The next reply, or None when the servo closed the connection first."""
    data = b""
    while len(data) < 4 or len(data) < 4 + struct.unpack(">I", data[:4])[0]:
        chunk = sock.recv(65536)
        if not chunk:
            return None
        data += chunk
    (length,) = struct.unpack(">I", data[:4])
    return json.loads(data[4 : 4 + length])


def rightful_hello(port: int, token: str | None) -> tuple[float, dict | None, socket.socket]:
    """Connects, says hello; the time to the answer (s), the answer and the open socket."""
    start = time.monotonic()
    sock = socket.create_connection(("127.0.0.1", port), timeout=5)
    sock.settimeout(5)
    sock.sendall(hello_text(token))
    try:
        reply = read_reply(sock)
    except OSError:
        reply = None
    return time.monotonic() - start, reply, sock


def rightful_hellos_during(port: int, token: str | None, seconds: float) -> list[float]:
    """Rightful hellos every 0.1 s for `seconds`; the time each took to be answered ok
    (inf for one refused, closed or unanswered)."""
    times = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        elapsed, reply, sock = rightful_hello(port, token)
        times.append(elapsed if reply is not None and reply.get("ok") else float("inf"))
        sock.close()
        time.sleep(0.1)
    return times


def report(attack: str, times: list[float]) -> None:
    answered = sum(t <= ANSWER_WITHIN_S for t in times)
    print(
        f"\n{attack}: {answered} of {len(times)} rightful hellos answered within "
        f"{ANSWER_WITHIN_S:g} s (slowest {max(times) * 1e3:.1f} ms)"
    )
    assert answered == len(times), f"{attack}: slowest {max(times):.3f} s"


class Attacker:
    """Threads running `attack(stop)` until stopped; counts what they did."""

    def __init__(self, attack, threads: int = 2):
        self.stop = threading.Event()
        self.count = 0
        self.lock = threading.Lock()
        self.threads = [
            threading.Thread(target=self._run, args=(attack,), daemon=True) for _ in range(threads)
        ]

    def _run(self, attack) -> None:
        while not self.stop.is_set():
            with contextlib.suppress(OSError):
                attack(self.stop)
            with self.lock:
                self.count += 1

    def __enter__(self) -> Attacker:
        for t in self.threads:
            t.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop.set()
        for t in self.threads:
            t.join(10)


def test_wrong_tokens_at_any_rate_never_keep_the_right_token_out(tmp_path):
    token_file = tmp_path / "token"
    token_file.write_text(TOKEN + "\n")

    def guess_without_waiting(stop: threading.Event) -> None:
        with socket.create_connection(("127.0.0.1", servo.port), timeout=2) as sock:
            sock.sendall(hello_text("a-wrong-guess-of-the-token-xxxxx"))

    def guess_and_wait(stop: threading.Event) -> None:
        with socket.create_connection(("127.0.0.1", servo.port), timeout=2) as sock:
            sock.settimeout(2)
            sock.sendall(hello_text("another-wrong-guess-yyyyyyyyyyy"))
            reply = read_reply(sock)  # None or "closed: ...": made room for newer ones
            assert reply is None or not reply["ok"], reply

    with ServoProcess([*LIVE, "--token-file", str(token_file)]) as servo:
        with Attacker(guess_without_waiting, 3) as fast, Attacker(guess_and_wait, 2) as waiting:
            times = rightful_hellos_during(servo.port, TOKEN, 4.0)
        print(f"\n{fast.count} wrong hellos sent without waiting, {waiting.count} waited for")
        report("wrong tokens from 5 threads", times)
        _, status_reply, sock = rightful_hello(servo.port, TOKEN)
        sock.sendall(struct.pack(">I", 17) + b'{"type":"status"}')
        protocol = read_reply(sock)["protocol"]
        assert protocol["wrong_tokens"] > 10 and servo.process.poll() is None
        sock.close()


def test_a_wrong_token_is_refused_after_a_delay_and_closes_its_connection(tmp_path):
    with ServoProcess([*LIVE, "--token", TOKEN]) as servo:
        elapsed, reply, sock = rightful_hello(servo.port, "not-the-token-at-all-zzzzzz")
        assert reply is not None and reply["error"] == "wrong or missing token"
        assert 0.4 < elapsed < 5.0, elapsed
        assert sock.recv(1) == b""  # closed: one try per connection
        sock.close()
        elapsed, reply, sock = rightful_hello(servo.port, TOKEN)
        assert reply is not None and reply["ok"], reply
        sock.close()


def test_a_short_token_is_refused_at_start():
    result = run_servo(*LIVE, "--token", "short", timeout_s=30)
    assert result.returncode == 2 and "at least 16" in result.stderr, result.stderr


def test_silent_and_slow_connections_hold_no_slot_and_meet_a_hello_deadline():
    with ServoProcess(LIVE) as servo:
        silent = [socket.create_connection(("127.0.0.1", servo.port)) for _ in range(40)]
        started = socket.create_connection(("127.0.0.1", servo.port))
        started.sendall(b"\x00")  # the first byte of a length, and nothing more

        def byte_a_second(stop: threading.Event) -> None:
            with socket.create_connection(("127.0.0.1", servo.port), timeout=2) as sock:
                for byte in hello_text(None)[:-1]:
                    if stop.wait(1.0):
                        return
                    sock.sendall(bytes([byte]))

        with Attacker(byte_a_second, 15):
            times = rightful_hellos_during(servo.port, None, 6.0)
        report("40 silent and 15 byte-a-second connections", times)
        # Past the hello deadline, a connection without its hello is told why and closed.
        started.settimeout(2)
        reply = read_reply(started)
        assert reply is not None and "no hello within" in reply["error"], reply
        for sock in [started, *silent]:
            sock.close()


def test_hundreds_of_connections_do_not_keep_a_client_out():
    with ServoProcess(LIVE) as servo:
        held: list[socket.socket] = []

        def open_and_hold(stop: threading.Event) -> None:
            sock = socket.create_connection(("127.0.0.1", servo.port), timeout=2)
            sock.sendall(b"\x00")  # something, so that each is accepted and waits
            held.append(sock)
            if len(held) > 300:
                held.pop(0).close()

        with Attacker(open_and_hold, 3) as opener:
            times = rightful_hellos_during(servo.port, None, 4.0)
        print(f"\n{opener.count} connections opened")
        report("connections opened (each sending a byte) as fast as 3 threads can", times)
        _, _, sock = rightful_hello(servo.port, None)
        sock.sendall(struct.pack(">I", 17) + b'{"type":"status"}')
        protocol = read_reply(sock)["protocol"]
        assert protocol["waiting_closed"] > 0, protocol
        for s in [sock, *held]:
            s.close()


def test_a_new_hello_closes_the_client_idle_longest_when_every_slot_is_taken():
    with ServoProcess(LIVE) as servo:
        holders = []
        for _ in range(16):
            _, reply, sock = rightful_hello(servo.port, None)
            assert reply is not None and reply["ok"]
            holders.append(sock)
        elapsed, reply, newcomer = rightful_hello(servo.port, None)
        print(f"\nall 16 slots held: the newcomer answered in {elapsed * 1e3:.1f} ms")
        assert reply is not None and reply["ok"] and elapsed < ANSWER_WITHIN_S
        closed = read_reply(holders[0])
        assert closed is not None and "idle longest" in closed["error"], closed
        for sock in [newcomer, *holders]:
            sock.close()
