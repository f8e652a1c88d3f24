"""The servo over loopback: each example scene, a sim stroke in real time, frames received,
and the proxies and ideal poses in the frames and in the recording equal an offline engine
run; a client of the old protocol is refused and told why."""

from __future__ import annotations

import time

import numpy as np
import pytest
from hapticut import servo_layout as layout
from hapticut.servo_client import PROTOCOL_VERSION, ServoClient, ServoError
from servo_test_support import (
    EXAMPLE_SCENES,
    SPHERE,
    ServoProcess,
    connect,
    offline_check,
    read_recording,
    wait_stopped,
)

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial


@pytest.mark.parametrize("scene", EXAMPLE_SCENES, ids=lambda p: p.name.split(".")[0])
def test_stream_and_recording_equal_offline_engine(scene, tmp_path):
    record = tmp_path / "run.rec"
    args = [str(scene), "--wait", "--engage", "--ramp", "0.05", "--exit-when-done"]
    args += ["--device", "scalpel=sim:press-slide,speed=300,hold_s=0.05", "--record", str(record)]
    with ServoProcess(args) as servo:
        client = connect(servo)
        client.blade_names = ["scalpel"]
        client.subscribe(rate_Hz=200)
        client.start()
        frames = wait_stopped(client, 30.0)
        client.close()
    assert len(frames) > 20, f"only {len(frames)} frames"
    sequences = [f.sequence for f in frames]
    assert sequences == sorted(sequences)

    recording = read_recording(record)
    ticks = recording.ticks["tick"]
    assert np.array_equal(ticks, np.arange(len(ticks)))  # every tick, none dropped
    assert int(recording.ticks["dropped_records"][-1]) == 0
    stepped = offline_check(scene, recording, "scalpel")
    assert stepped == len(recording)
    force = np.linalg.norm(recording.blade("scalpel")["block"]["engine_force_N"], axis=1)
    assert force.max() > 0.1, "the stroke never touched the scene"
    rendered = np.linalg.norm(recording.blade("scalpel")["block"]["force_N"], axis=1)
    assert np.all(rendered <= 5.0 + 1e-9) and rendered.max() > 0.1  # clamped to the scene's 5 N

    # Each frame is the recorded tick it names.
    q = recording.blade("scalpel")["q"]
    p = recording.blade("scalpel")["p"]
    for frame in frames:
        blade = frame.blades["scalpel"]
        k = int(frame.header["tick"])
        assert np.array_equal(blade["q"], q[k])
        assert np.array_equal(blade["p"], p[k])
        assert np.array_equal(frame.ideal_pose("scalpel"), recording.ideal_pose("scalpel")[k])
        assert int(blade["block"]["point_count"]) == 50
        assert int(blade["block"]["state_counts"].sum()) == 50
    last = frames[-1].header
    assert last["compute_p99_us"] > 0 and last["wake_p99_us"] > 0
    assert bytes(last["magic"].tobytes()) == layout.FRAME_MAGIC


def test_subscribe_rate_and_newest_wins(tmp_path):
    """A slow client only drops frames: after sleeping, poll() hands the newest."""
    from servo_test_support import SPHERE

    args = [str(SPHERE), "--device", "sim:press-slide,speed=20", "--engage"]
    with ServoProcess(args) as servo:
        client = connect(servo, ["scalpel"])
        client.subscribe(rate_Hz=100)
        time.sleep(0.5)
        newest = client.poll()
        assert newest is not None
        again = client.poll()  # drained: nothing, or only newer frames
        assert again is None or again.sequence > newest.sequence
        newest = again or newest
        time.sleep(0.3)
        frames = client.poll_all()
        assert 10 <= len(frames) <= 60  # ~100 Hz for 0.3 s
        assert frames[0].sequence > newest.sequence
        status = client.status()
        assert status["state"] == "running" and status["protocol"]["subscribers"] == 1


def test_record_by_message_while_running(tmp_path):
    from servo_test_support import SPHERE

    record = tmp_path / "message.rec"
    args = [str(SPHERE), "--device", "sim:press-slide,speed=20", "--engage"]
    with ServoProcess([*args, "--record-dir", str(tmp_path)]) as servo:
        client = connect(servo)
        time.sleep(0.2)
        assert client.record(record)["recording"] == str(record)
        time.sleep(0.5)
        reply = client.stop_recording()
        assert reply["written"] > 300 and reply["dropped"] == 0
        assert client.status()["state"] == "running"
    recording = read_recording(record)
    assert len(recording) == reply["written"]
    ticks = recording.ticks["tick"]
    assert ticks[0] > 100 and np.array_equal(np.diff(ticks), np.ones(len(ticks) - 1))


def test_a_recording_that_cannot_be_written_is_reported_while_running(tmp_path):
    """Writes that fail (here past a file size limit, SIGXFSZ ignored) are the recorder
    thread's to note while the control thread reports them: status names the error, the run
    goes on. Under ThreadSanitizer (tests/scripts/tsan.sh) this is where the two meet."""
    from hapticut import servo_path
    from servo_test_support import SPHERE

    record = tmp_path / "limited.rec"
    # dash counts ulimit -f in 512-byte blocks: 1 MiB, a few hundred records.
    limited = ["-c", 'trap "" XFSZ; ulimit -f 2048; exec "$0" "$@"', servo_path()]
    args = [*limited, str(SPHERE), "--device", "sim:press-slide,speed=20", "--engage"]
    args += ["--record-dir", str(tmp_path)]
    with ServoProcess(args, executable="/bin/sh") as servo:
        client = connect(servo)
        assert client.record(record)["recording"] == str(record)
        errors = []
        for _ in range(3000):  # until the limit is reached (well within 30 s)
            errors.append(client.status()["recording"]["error"])
            if errors[-1]:
                break
            time.sleep(0.01)
        client.stop_recording()
        assert client.status()["state"] == "running"
    assert errors[-1] == "write failed: File too large", errors[-1]


def test_a_client_of_the_old_protocol_is_refused_and_told_to_update():
    """Older clients read frames without the cut tets (and version 1 blade blocks without the
    ideal pose): they would misread every frame, so hello refuses them, and the connection
    then works with the current version."""
    assert PROTOCOL_VERSION == 3 and layout.FRAME_VERSION == 4 and layout.RECORD_VERSION == 5
    with ServoProcess([str(SPHERE), "--device", "scalpel=sim", "--wait"]) as servo:
        old = ServoClient(port=servo.port).connect()
        with pytest.raises(ServoError) as refused:
            old.request("hello", version=1)
        with pytest.raises(ServoError, match='before "hello"'):
            old.subscribe(rate_Hz=100)
        reply = old.hello()
        old.close()
        assert servo.stop() == 0
    assert str(refused.value).endswith(
        "protocol version 1 not supported (this servo speaks version 3, whose frames and "
        "recordings carry the cut tets; update the client: the hapticut toolkit and the add-on "
        "of this servo's release)"
    )
    assert (reply["version"], reply["frame_version"], reply["record_version"]) == (3, 4, 5)


def test_a_client_of_other_layouts_refuses_the_servo(monkeypatch):
    """The same protocol version with another frame layout would be misread frame by frame:
    the client says so at hello rather than parse frames it cannot read."""
    servo_writes = layout.FRAME_VERSION
    monkeypatch.setattr(layout, "FRAME_VERSION", servo_writes - 1)  # the client's layouts
    with ServoProcess([str(SPHERE), "--device", "scalpel=sim", "--wait"]) as servo:
        client = ServoClient(port=servo.port)
        with pytest.raises(ServoError) as refused:
            client.hello()
        client.close()
        assert servo.stop() == 0
    assert str(refused.value) == (
        f"the servo writes frame version {servo_writes}, this client reads version "
        f"{servo_writes - 1}: use the hapticut toolkit of the servo's release"
    )


def test_a_frame_carries_the_ideal_pose():
    """A viewport pose in, the engine's ideal pose out: independent points report the device's
    pose (normalised), a rigid blade its own (the layout's field, and StreamFrame.ideal_pose)."""
    with ServoProcess([str(SPHERE), "--device", "scalpel=viewport"]) as servo:
        client = connect(servo, ["scalpel"])
        client.subscribe(rate_Hz=200)
        pose = [1.0, 2.0, 60.0, 2.0, 0.0, 0.0, 0.0]  # above the ball; a quaternion of norm 2
        frame = None
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            client.send_pose("scalpel", pose)
            newest = client.poll()
            if newest is not None and int(newest.blades["scalpel"]["block"]["step_kind"]):
                frame = newest
                break
            time.sleep(0.01)
        coupling = client.status()["blades"][0]["coupling"]
        client.close()
    assert frame is not None, "no frame of a stepped tick"
    ideal = frame.ideal_pose("scalpel")
    assert np.array_equal(ideal, layout.ideal_pose(frame.blades["scalpel"]))
    assert ideal.shape == (7,)
    # In the air both couplings put the ideal pose on the device's, normalised.
    assert np.allclose(ideal, [1.0, 2.0, 60.0, 1.0, 0.0, 0.0, 0.0]), (coupling, ideal)
    assert np.array_equal(frame.blades["scalpel"]["block"]["pose"], pose)
