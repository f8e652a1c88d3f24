"""The device texts of `load` obey the file rules of every path the servo opens
(docs/protocol.md, "Files"): a `sim:` path or a `replay:` recording is a regular file,
opened without waiting, bounded in size or read a part at a time, and never quoted in an
error; a bridge binds only to loopback unless the operator's command line says otherwise
with a token. Each test drives the real binary over loopback."""

from __future__ import annotations

import os
import threading
import time

import pytest
from hapticut.servo_client import ServoClient, ServoError
from servo_test_support import SPHERE, ServoProcess, bake, connect, run_servo

TOKEN = "operator-token-0123456789abcdef"


def rss_mb(pid: int) -> float:
    with open(f"/proc/{pid}/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise AssertionError("no VmRSS")


def answered_while(servo: ServoProcess, action) -> float:
    """Runs action() on a thread; the slowest `status` another client got meanwhile (s)."""
    other = connect(servo)
    done = threading.Event()
    slowest = [0.0]

    def run() -> None:
        try:
            action()
        finally:
            done.set()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    while not done.is_set():
        start = time.monotonic()
        other.status()
        slowest[0] = max(slowest[0], time.monotonic() - start)
        time.sleep(0.01)
    thread.join(30)
    other.close()
    return slowest[0]


def test_a_sim_path_that_is_not_a_regular_file_is_refused_at_once(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    with ServoProcess(["--device", "sim"]) as servo:
        client = connect(servo)
        for path, kind in ((fifo, "a FIFO"), ("/dev/zero", "a character device")):
            start = time.monotonic()
            with pytest.raises(ServoError, match=f"not a regular file \\({kind}\\)"):
                client.load(SPHERE, devices=[f"sim:{path}"])
            print(f"\nsim:{path} refused in {(time.monotonic() - start) * 1e3:.1f} ms")
        assert client.status()["state"] == "idle"


def test_a_sim_path_over_the_size_limit_is_refused_on_its_size(tmp_path):
    big = tmp_path / "big.json"
    with open(big, "wb") as f:
        f.truncate(17 << 20)  # sparse: nothing is written
    with ServoProcess(["--device", "sim"]) as servo:
        client = connect(servo)
        with pytest.raises(ServoError, match=r"over the limit of 16\.0 MiB"):
            client.load(SPHERE, devices=[f"sim:{big}"])


def test_a_sim_path_error_never_quotes_the_file(tmp_path):
    secret = tmp_path / "path.json"
    secret.write_text("secret-content-12345 {")
    wrong = tmp_path / "wrong.json"
    wrong.write_text('{"poses": [["secret-value", 0, 0, 0, 1, 0, 0, 0]]}')
    with ServoProcess(["--device", "sim"]) as servo:
        client = connect(servo)
        for path in (secret, wrong):
            with pytest.raises(ServoError) as caught:
                client.load(SPHERE, devices=[f"sim:{path}"])
            message = str(caught.value).replace(str(path), "")
            print(f"\n{message}")
            assert "secret" not in message and "12345" not in message
            assert "json.exception" not in message
        assert "/poses/0/0: not a finite number" in str(caught.value)


def test_a_large_replay_is_opened_at_once_and_played_in_bounded_memory(tmp_path):
    source = tmp_path / "source.rec"
    bake(SPHERE, source, "sim:press,speed=20")
    big = tmp_path / "big.rec"
    # A real header, then 2 GiB of records the file system does not store (zeros: a
    # device that is "fresh" at the origin with a zero rotation, which the engine refuses).
    header_bytes = 16 + int.from_bytes(source.read_bytes()[8:16], "little")
    big.write_bytes(source.read_bytes()[:header_bytes])
    with open(big, "r+b") as f:
        f.truncate(header_bytes + (2 << 30))
    with ServoProcess(["--device", "sim"]) as servo:
        client = connect(servo)
        before = rss_mb(servo.process.pid)
        loading = {}

        def load() -> None:
            start = time.monotonic()
            client.load(SPHERE, devices=[f"replay:{big}"])
            loading["s"] = time.monotonic() - start
            client.start()
            time.sleep(1.5)

        slowest = answered_while(servo, load)
        during = rss_mb(servo.process.pid)
        ticks = client.status()["ticks"]
        print(
            f"\nreplay of a 2 GiB recording: loaded in {loading['s'] * 1e3:.1f} ms, RSS "
            f"{before:.0f} MB before, {during:.0f} MB after {ticks} ticks; another client's "
            f"slowest status {slowest * 1e3:.1f} ms"
        )
        assert loading["s"] < 1.0 and slowest < 1.0
        assert during - before < 64, (before, during)
        assert ticks > 500 and client.status()["state"] == "running"


def test_a_bridge_binds_beyond_loopback_only_on_the_operators_word(tmp_path):
    with ServoProcess(["--device", "sim"]) as servo:
        client = connect(servo)
        with pytest.raises(ServoError, match="a bridge binds only to loopback"):
            client.load(SPHERE, devices=["bridge:port=0,bind=0.0.0.0"])
        loaded = client.load(SPHERE, devices=["bridge:port=0,bind=127.0.0.1"])
        assert loaded["blades"][0]["kind"] == "bridge"
    result = run_servo(str(SPHERE), "--device", "bridge:port=0,bind=0.0.0.0", "--duration", "0.1")
    assert result.returncode == 4 and "a bridge binds only to loopback" in result.stderr
    # The operator's command line with a token may; a client's load still may not.
    args = [str(SPHERE), "--device", "bridge:port=0,bind=0.0.0.0", "--token", TOKEN]
    with ServoProcess(args) as servo:
        client = ServoClient(port=servo.port, token=TOKEN)
        client.hello()
        assert client.status()["blades"][0]["kind"] == "bridge"
        client.stop()
        with pytest.raises(ServoError, match="a bridge binds only to loopback"):
            client.load(SPHERE, devices=["bridge:port=0,bind=0.0.0.0"])
