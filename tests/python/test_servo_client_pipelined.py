"""ServoClient.send_request / replies (the add-on's live timer never waits for a reply) and
poll_newest (bounded), against the real servo over loopback."""

import time
from pathlib import Path

import pytest
from hapticut.servo_client import ServoClient, ServoError, ServoProcess

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial

FINGER = Path(__file__).resolve().parents[2] / "examples" / "finger.hapticut.msgpack"


@pytest.fixture()
def servo():
    with ServoProcess([str(FINGER), "--wait", "--device", "scalpel=viewport", "--quiet"]) as s:
        yield s


def wait_for(replies_of, count: int, timeout_s: float = 10.0) -> list[dict]:
    got, began = [], time.monotonic()
    while len(got) < count:
        got += replies_of()
        assert time.monotonic() - began < timeout_s
        time.sleep(0.001)
    return got


def test_replies_come_in_order_without_waiting(servo):
    client = ServoClient(port=servo.port).connect()
    client.hello()
    began = time.perf_counter()
    ids = [client.send_request("status"),
           client.send_request("pose", blade="scalpel", pose=[0, 0, 20, 1, 0, 0, 0]),
           client.send_request("pose", blade="nobody", pose=[0, 0, 20, 1, 0, 0, 0])]  # fmt: skip
    assert time.perf_counter() - began < 0.5
    assert client.unanswered == 3
    got = wait_for(client.replies, 3)
    assert [r["id"] for r in got] == ids
    assert got[0]["type"] == "status" and got[0]["ok"]
    assert got[1]["ok"] and not got[2]["ok"] and "no blade 'nobody'" in got[2]["error"]
    assert client.unanswered == 0 and client.replies() == []
    # A request waits for its own reply; the earlier unanswered ones are kept for replies().
    first = client.send_request("status")
    assert client.request("status")["ok"]
    assert [r["id"] for r in client.replies()] == [first]


def test_a_closed_connection_is_an_error(servo):
    client = ServoClient(port=servo.port).connect()
    client.hello()
    client.send_request("shutdown")
    assert wait_for(client.replies, 1)[0]["ok"]
    assert servo.wait(10) == 0
    with pytest.raises((ServoError, OSError)):  # A refused send, or the closed connection.
        client.send_request("status")
        wait_for(client.replies, 1)


def test_poll_newest_reads_at_most_its_bound(servo):
    client = ServoClient(port=servo.port).connect()
    client.hello()
    client.subscribe(rate_Hz=500)
    client.start()
    time.sleep(0.5)  # About 250 frames waiting.
    frame = client.poll_newest(max_datagrams=10, budget_s=1.0)
    assert frame is not None and client.datagrams_read == 10
    newer = client.poll_newest(max_datagrams=1000, budget_s=1.0)
    assert newer.sequence > frame.sequence
    assert client.poll_newest() is None or client.datagrams_read > 10
