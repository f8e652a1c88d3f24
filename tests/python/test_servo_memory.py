"""The control channel's memory is bounded and given back (docs/protocol.md, "Budgets"):
clients that pipeline the largest messages the protocol allows raise the servo's memory by
at most the documented cap plus one message being handled, and it returns after the burst.
The real binary over loopback; the resident set before, during and after is printed."""

from __future__ import annotations

import json
import socket
import struct
import threading
import time

from hapticut.servo_client import PROTOCOL_VERSION
from servo_test_support import SPHERE, ServoProcess

LIVE = [str(SPHERE), "--device", "sim:press-slide,speed=20", "--engage"]
MiB = 1 << 20
LARGE_MESSAGES_CAP = 64 * MiB  # kMaxLargeMessageBytes, server/control_server.h
ONE_MESSAGE = 16 * MiB


def rss_bytes(pid: int) -> int:
    with open(f"/proc/{pid}/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise AssertionError("no VmRSS")


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


def send(sock: socket.socket, text: bytes) -> None:
    sock.sendall(struct.pack(">I", len(text)) + text)


def test_large_messages_from_many_clients_stay_within_the_cap_and_memory_returns():
    with ServoProcess(LIVE) as servo:
        pid = servo.process.pid
        clients = []
        for _ in range(6):
            sock = socket.create_connection(("127.0.0.1", servo.port), timeout=60)
            send(sock, json.dumps({"type": "hello", "version": PROTOCOL_VERSION}).encode())
            assert read_reply(sock)["ok"]
            clients.append(sock)
        time.sleep(0.5)
        before = rss_bytes(pid)
        padding = b"x" * (ONE_MESSAGE - 64)
        big = b'{"type":"status","pad":"' + padding + b'"}'
        peak = [before]
        done = threading.Event()

        def sample() -> None:
            while not done.is_set():
                peak[0] = max(peak[0], rss_bytes(pid))
                time.sleep(0.005)

        def burst(sock: socket.socket) -> None:
            for _ in range(3):  # pipelined: sent before any reply is read
                send(sock, big)
            for _ in range(3):
                reply = read_reply(sock)
                assert not reply["ok"] and reply["error"].startswith("unknown field 'pad'")

        sampler = threading.Thread(target=sample, daemon=True)
        sampler.start()
        senders = [threading.Thread(target=burst, args=(s,)) for s in clients]
        for t in senders:
            t.start()
        for t in senders:
            t.join(120)
        time.sleep(0.5)
        done.set()
        sampler.join(5)
        after = rss_bytes(pid)
        print(
            f"\n18 messages of 16 MiB from 6 clients: RSS {before / MiB:.0f} MB before, "
            f"{peak[0] / MiB:.0f} MB at most during, {after / MiB:.0f} MB after"
        )
        # The cap (the message being handled among them), plus what decoding it takes.
        assert peak[0] - before <= LARGE_MESSAGES_CAP + 5 * ONE_MESSAGE
        assert after - before <= 16 * MiB
        for sock in clients:
            send(sock, b'{"type":"status"}')
            assert read_reply(sock)["state"] == "running"
            sock.close()
