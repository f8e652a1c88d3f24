"""A `load` is read, parsed and built off the control thread (docs/protocol.md, "Files";
docs/decisions.md, "A load is built on a worker"): while one client's large scene loads, every
other client is answered; the loading client's own later messages wait for its reply, which
keeps its shape; a client gone mid-load cancels it and the old scene stays; `shutdown` and
SIGTERM end the servo without waiting for the load. Each test drives the real binary over
loopback with a scene whose load alone takes over a second here (measured first, printed).
What is asserted is order (answered before the load's reply), not time, except that a
shutdown ends the servo sooner than the load alone took."""

from __future__ import annotations

import dataclasses
import time

import pytest
from hapticut.scenefile import BladeSpec, save_scene
from hapticut.servo_client import ServoClient, ServoError
from scene_test_support import grid_scene
from servo_test_support import SPHERE, ServoProcess, connect

pytestmark = pytest.mark.serial

# A load alone takes at least this long, so that the other clients' answers have
# time to come before it ends by a wide margin.
MIN_LOAD_S = 1.5
SIM = ["--device", "sim"]


@dataclasses.dataclass
class BigScene:
    path: str
    load_s: float  # One load of it alone, on an idle servo.


def timed_load(path: str) -> float:
    with ServoProcess(SIM) as servo:
        client = ServoClient(port=servo.port, timeout_s=300)
        client.hello()
        start = time.monotonic()
        client.load(path)
        return time.monotonic() - start


@pytest.fixture(scope="module")
def big_scene(tmp_path_factory) -> BigScene:
    """A grid of Kuhn tets just large enough that loading it takes over MIN_LOAD_S on this
    machine and build (a sanitizer's build stops at a smaller one)."""
    cells = 20
    while True:
        scene = grid_scene(cells)
        top = cells - 0.5
        blade = BladeSpec("scalpel", (0.5, 0.5, top), (cells - 0.5, 0.5, top), 50)
        path = tmp_path_factory.mktemp("big") / f"grid{cells}.hapticut.msgpack"
        save_scene(dataclasses.replace(scene, blades=[blade]), path)
        load_s = timed_load(str(path))
        print(
            f"\n{len(scene.tets)} tets ({path.stat().st_size / 1e6:.1f} MB): "
            f"loaded in {load_s:.2f} s"
        )
        if load_s > MIN_LOAD_S or cells >= 80:
            assert load_s > MIN_LOAD_S, "no grid loads slowly enough to tell the order"
            return BigScene(str(path), load_s)
        cells = int(cells * 1.25) + 1


def loading_seen_by(client: ServoClient) -> dict:
    """A status of `client` that says a load is on its way (asked until one does)."""
    for _ in range(500):
        status = client.status()
        if status["loading"]:
            return status
        time.sleep(0.01)
    raise AssertionError("the load never showed in status")


def reply_to(client: ServoClient, timeout_s: float = 300.0) -> list[dict]:
    """The replies to the requests `client` sent without waiting, once they are all in."""
    replies: list[dict] = []
    deadline = time.monotonic() + timeout_s
    while client.unanswered and time.monotonic() < deadline:
        replies += client.replies()
        time.sleep(0.005)
    return replies


def test_other_clients_are_answered_while_a_large_scene_loads(big_scene):
    with ServoProcess(SIM) as servo:
        loader = ServoClient(port=servo.port, timeout_s=300)
        loader.hello()
        sent = time.monotonic()
        load_id = loader.send_load(big_scene.path)
        status_id = loader.send_request("status")  # Waits behind its own load.

        start = time.monotonic()
        other = connect(servo)
        during = loading_seen_by(other)
        answered_s = time.monotonic() - start
        stop = other.stop()
        with pytest.raises(ServoError, match="a load is in progress"):
            other.start()
        with pytest.raises(ServoError, match="another load is in progress"):
            other.load(SPHERE)
        # All of that was answered before the load's own reply.
        assert loader.replies() == []
        assert during["state"] == "idle" and stop["stats"] is None

        load, status = reply_to(loader)
        loaded_s = time.monotonic() - sent
        print(
            f"\nanother client's hello and status: {answered_s * 1e3:.1f} ms, while the "
            f"load took {loaded_s:.2f} s (alone: {big_scene.load_s:.2f} s)"
        )
        # The reply keeps its shape, and the loader's next message came after it.
        assert load["id"] == load_id and status["id"] == status_id
        loader.loaded(load)
        assert load["blades"][0]["name"] == "scalpel" and load["rate_Hz"] == 1000
        assert status["state"] == "loaded" and not status["loading"]
        assert status["scene"] == big_scene.path
        assert other.status()["state"] == "loaded"
        assert loader.start()["session"] == 1


def test_a_client_gone_mid_load_cancels_it_and_the_old_scene_stays(big_scene):
    with ServoProcess(SIM) as servo:
        other = connect(servo)
        other.load(SPHERE)
        loader = connect(servo)
        loader.send_load(big_scene.path)
        loading_seen_by(other)
        loader.close()
        gone = time.monotonic()
        deadline = gone + 300
        while other.status()["loading"] and time.monotonic() < deadline:
            time.sleep(0.01)
        status = other.status()
        print(f"\nthe load ended {time.monotonic() - gone:.2f} s after its client left")
        assert servo.process.poll() is None
        assert not status["loading"] and status["state"] == "loaded"
        assert status["scene"] == str(SPHERE)
        assert not any(big_scene.path in line for line in servo.lines)
        # The worker is free again.
        assert other.load(SPHERE)["blades"][0]["name"] == "scalpel"


@pytest.mark.parametrize("how", ["shutdown", "SIGTERM"])
def test_shutdown_during_a_load_does_not_wait_for_it(big_scene, how):
    with ServoProcess(SIM) as servo:
        loader = connect(servo)
        loader.send_load(big_scene.path)
        other = connect(servo)
        loading_seen_by(other)
        start = time.monotonic()
        if how == "shutdown":
            other.shutdown()
        else:
            servo.process.terminate()
        code = servo.wait(300)
        ended_s = time.monotonic() - start
        print(f"\n{how} during a load: the servo ended in {ended_s * 1e3:.0f} ms (exit {code})")
        assert code == 0, servo.stderr_lines[-5:]
        # Sooner than the load alone took: it did not wait for the load.
        assert ended_s < big_scene.load_s
        with pytest.raises(ServoError, match="closed the connection"):
            reply_to(loader, timeout_s=5)
