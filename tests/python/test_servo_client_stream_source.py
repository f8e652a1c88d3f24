"""The project's client takes stream frames from the servo's stream socket only
(``stream_source_port``): a well-formed frame forged by another local sender is ignored
and counted, however new it claims to be."""

from __future__ import annotations

import socket
import time

import numpy as np
import pytest
from hapticut import servo_layout as layout
from hapticut.servo_client import parse_stream_frame
from servo_test_support import SPHERE, ServoProcess, connect

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial

FORGED_SESSION = 1 << 31
FORGED_SEQUENCE = 1 << 62


def forged_frame(points: int) -> bytes:
    """A frame that parses, from the newest run there could be."""
    frame = np.zeros((), layout.stream_frame_dtype([points]))
    header = frame["header"]
    header["magic"] = np.frombuffer(layout.FRAME_MAGIC, "S1")
    header["version"] = layout.FRAME_VERSION
    header["blade_count"] = 1
    header["frame_bytes"] = frame.dtype.itemsize
    header["session"] = FORGED_SESSION
    header["sequence"] = FORGED_SEQUENCE
    frame["blade0"]["block"]["point_count"] = points
    frame["blade0"]["block"]["force_N"] = [100.0, 0.0, 0.0]
    data = frame.tobytes()
    assert parse_stream_frame(data).order == (FORGED_SESSION, FORGED_SEQUENCE)
    return data


def wait_for_frames(client, poll) -> list:
    """Frames from the servo (it streams at 200 Hz; each call returns what has come)."""
    while True:
        frames = poll()
        if frames:
            return frames
        time.sleep(0.01)


def test_forged_datagrams_from_another_port_are_ignored_and_counted():
    with ServoProcess([str(SPHERE), "--device", "scalpel=sim"]) as servo:
        client = connect(servo, ["scalpel"])
        reply = client.subscribe(rate_Hz=200)
        assert client.stream_source == ("127.0.0.1", reply["stream_source_port"])
        stream_port = client._stream.getsockname()[1]
        points = len(wait_for_frames(client, client.poll_all)[-1].blades["scalpel"]["q"])
        forged = forged_frame(points)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as forger:
            forger.bind(("127.0.0.1", 0))
            assert forger.getsockname()[1] != reply["stream_source_port"]

            for _ in range(5):
                forger.sendto(forged, ("127.0.0.1", stream_port))
            frames = wait_for_frames(client, client.poll_all)
            assert client.foreign_datagrams == 5
            assert all(f.session < FORGED_SESSION for f in frames)
            assert all(float(f.blades["scalpel"]["block"]["force_N"][0]) != 100.0 for f in frames)

            for _ in range(3):
                forger.sendto(forged, ("127.0.0.1", stream_port))
            # One call reads all that waits (the forged ones too); later calls, what came since.
            newest = [client.poll_newest(max_datagrams=1000, budget_s=1.0)]
            assert client.foreign_datagrams == 8
            if newest[0] is None:
                newest = wait_for_frames(client, lambda: [f for f in [client.poll_newest()] if f])
            assert newest[0].session < FORGED_SESSION
        client.close()
