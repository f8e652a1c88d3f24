"""The control channel is as strict as docs/protocol.md says ("Parsing"): every message
refuses the fields it does not take, naming them; integers are checked against both ends of
their range; a byte order mark and an escaped NUL are refused; a bad scene's error names its
field, including what only the engine checks. The real binary over loopback."""

from __future__ import annotations

import copy
import json
import struct

import pytest
from hapticut.scenefile import load_scene, save_scene
from hapticut.servo_client import PROTOCOL_VERSION
from servo_test_support import SPHERE, ServoProcess

UNKNOWN_FIELDS = {
    "subscribe": {"port": 5000, "address": "10.0.0.1"},
    "status": {"verbose": True},
    "start": {"now": 1},
    "stop": {"force": True},
    "unsubscribe": {"port": 5000},
    "engage": {"engaged": False, "hand": "left"},
    "record": {"action": "stop", "overwrite": True},
    "pose": {"blade": "scalpel", "pose": [0, 0, 0, 1, 0, 0, 0], "speed": 1},
    "load": {"path": "x.hapticut.json", "validate": False},
    "shutdown": {"now": True},
}


def ask(sock, payload: bytes) -> dict:
    sock.sendall(struct.pack(">I", len(payload)) + payload)
    data = b""
    while len(data) < 4 or len(data) < 4 + struct.unpack(">I", data[:4])[0]:
        chunk = sock.recv(65536)
        assert chunk, "the servo closed the connection"
        data += chunk
    return json.loads(data[4:])


@pytest.fixture
def servo_socket():
    import socket

    with ServoProcess(["--device", "sim"]) as servo:
        sock = socket.create_connection(("127.0.0.1", servo.port), timeout=10)
        hello = {"type": "hello", "version": PROTOCOL_VERSION, "client": "x"}
        reply = ask(sock, json.dumps(hello).encode())
        assert not reply["ok"] and reply["error"].startswith("unknown field 'client'"), reply
        del hello["client"]
        assert ask(sock, json.dumps(hello).encode())["ok"]
        yield servo, sock
        sock.close()


def test_every_message_refuses_fields_it_does_not_take(servo_socket):
    servo, sock = servo_socket
    for kind, fields in UNKNOWN_FIELDS.items():
        reply = ask(sock, json.dumps({"type": kind, **fields}).encode())
        assert not reply["ok"] and reply["error"].startswith("unknown field '"), (kind, reply)
        assert f'"{kind}" takes' in reply["error"], reply
    assert servo.process.poll() is None
    reply = ask(sock, b'{"type":"set","colour":1}')
    assert not reply["ok"] and "unknown parameter 'colour'" in reply["error"]


def test_integers_are_checked_at_both_ends(servo_socket):
    _, sock = servo_socket
    for port in (0, -1, 65536):
        reply = ask(sock, json.dumps({"type": "subscribe", "port": port}).encode())
        assert not reply["ok"] and reply["error"].startswith("port: out of range"), reply
    reply = ask(sock, b'{"type":"pose","blade":"b","pose":[0,0,0,1,0,0,0],"buttons":-1}')
    assert not reply["ok"] and reply["error"].startswith("buttons: out of range"), reply


def test_a_byte_order_mark_and_an_escaped_nul_are_refused(servo_socket):
    _, sock = servo_socket
    reply = ask(sock, b'\xef\xbb\xbf{"type":"status"}')
    assert not reply["ok"] and "byte order mark" in reply["error"]
    reply = ask(sock, b'{"type":"load","path":"a\\u0000.hapticut.json"}')
    assert not reply["ok"] and "\\u0000" in reply["error"]
    assert ask(sock, b'{"type":"status"}')["ok"]


def test_load_takes_a_path_or_a_scene_not_both(servo_socket):
    _, sock = servo_socket
    reply = ask(sock, json.dumps({"type": "load", "path": "a", "scene": {}}).encode())
    assert not reply["ok"] and "not both" in reply["error"]


def test_every_bad_scene_names_its_field(servo_socket, tmp_path):
    _, sock = servo_socket
    save_scene(load_scene(SPHERE), tmp_path / "s.hapticut.json")
    base = json.loads((tmp_path / "s.hapticut.json").read_text())

    def points(n):
        return lambda s: s["blades"][0].__setitem__("points", n)

    def repeated_tet(s):
        s["mesh"]["tets"][1] = s["mesh"]["tets"][0]

    cases = {
        "/blades/0": points(100_000),  # over the engine's own limit
        "/blades": points(5000),  # a frame over a datagram
        "/mesh/tets": repeated_tet,
        "/coupling/servo_rate_Hz": lambda s: s["coupling"].__setitem__("servo_rate_Hz", 0.5),
        "/blades/0/points": points(0),
    }
    for field, change in cases.items():
        scene = copy.deepcopy(base)
        change(scene)
        reply = ask(sock, json.dumps({"type": "load", "scene": scene}).encode())
        print(f"\n{reply['error']}")
        assert not reply["ok"] and reply["error"].startswith(f"scene: {field}: "), reply
        assert "internal error" not in reply["error"]
