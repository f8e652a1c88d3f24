"""The recording's end: every clean close writes the trailer (record count, records dropped,
end marker), so a file cut short - even by SIGKILL exactly on a record boundary - reads as
truncated, with every whole record, and the replay device plays it and says so."""

from __future__ import annotations

import os
import signal
import subprocess
import time

import numpy as np
import pytest
from hapticut import servo_layout as layout
from hapticut import servo_path
from hapticut.recording import RecordingError
from servo_test_support import (
    SPHERE,
    ServoProcess,
    bake,
    connect,
    read_recording,
    run_servo,
)

# Times a real servo's clock-paced threads: runs alone, never beside other tests
# (tests/run_all.sh runs the serial tests after the parallel ones).
pytestmark = pytest.mark.serial

TRAILER = layout.RECORDING_TRAILER.itemsize


def records_start(path) -> int:
    """Where the first record begins (after the magic, the length and the header)."""
    data = open(path, "rb").read(16)  # noqa: SIM115
    return 16 + int.from_bytes(data[8:16], "little")


def whole_records(path) -> int:
    """Whole records in a recording being written (0 before its header is all there)."""
    try:
        return len(read_recording(path))
    except (OSError, RecordingError):
        return 0


def cut(source, target, size: int):
    target.write_bytes(source.read_bytes()[:size])
    return target


@pytest.fixture(scope="module")
def stroke(tmp_path_factory):
    """A complete recording of a sim stroke and its run's statistics."""
    path = tmp_path_factory.mktemp("stroke") / "stroke.rec"
    stats = bake(SPHERE, path, "scalpel=sim:press-slide")
    return path, stats


def test_a_cleanly_closed_recording_ends_with_its_trailer(stroke):
    path, stats = stroke
    recording = read_recording(path)
    assert not recording.truncated and recording.problem == ""
    assert len(recording) == stats["ticks"] == stats["recording"]["written"] > 100
    assert recording.dropped_records == 0
    data = path.read_bytes()
    assert data.endswith(layout.RECORDING_END_MARKER)
    trailer = np.frombuffer(data[-TRAILER:], layout.RECORDING_TRAILER)[0]
    assert int(trailer["record_count"]) == len(recording)
    assert len(data) == records_start(path) + len(recording) * recording.records.itemsize + TRAILER


def test_cut_on_a_record_boundary_is_truncated_with_every_whole_record(stroke, tmp_path):
    path, _ = stroke
    complete = read_recording(path)
    boundary = cut(path, tmp_path / "boundary.rec", path.stat().st_size - TRAILER)
    recording = read_recording(boundary)
    assert recording.truncated and recording.truncated_bytes == 0
    assert recording.records.tobytes() == complete.records.tobytes()
    assert recording.problem == (
        f"recording {str(boundary)!r} is truncated (no end trailer: the run was cut short): "
        f"{len(complete)} whole records"
    )
    # Inside the trailer, and inside the last record: the records before the cut.
    for size, whole in (
        (path.stat().st_size - 1, len(complete)),
        (path.stat().st_size - TRAILER - 1, len(complete) - 1),
    ):
        recording = read_recording(cut(path, tmp_path / "inside.rec", size))
        assert recording.truncated and len(recording) == whole
        assert recording.records.tobytes() == complete.records[:whole].tobytes()
        assert f"{whole} whole records, a partial last record of" in recording.problem


def test_a_trailer_that_miscounts_is_refused(stroke, tmp_path):
    path, _ = stroke
    data = path.read_bytes()
    record_bytes = read_recording(path).records.itemsize
    damaged = tmp_path / "damaged.rec"
    damaged.write_bytes(data[: -TRAILER - record_bytes] + data[-TRAILER:])
    count = len(read_recording(path))
    with pytest.raises(RecordingError) as error:
        read_recording(damaged)
    assert str(error.value) == (
        f"recording {str(damaged)!r}: damaged: its trailer counts {count} records, "
        f"the file holds {count - 1}"
    )


def test_replay_of_a_truncated_recording_plays_its_whole_records_and_says_so(stroke, tmp_path):
    path, _ = stroke
    complete = read_recording(path)
    keep = len(complete) // 2
    start = records_start(path)
    truncated = cut(path, tmp_path / "half.rec", start + keep * complete.records.itemsize)
    replayed = tmp_path / "replayed.rec"
    args = [str(SPHERE), "--as-fast-as-possible", "--exit-when-done", "--engage"]
    result = run_servo(*args, "--device", f"scalpel=replay:{truncated}", "--record", str(replayed))
    assert result.returncode == 0, result.stderr
    assert (
        f"recording '{truncated}' is truncated (no end trailer: the run was cut short): "
        f"{keep} whole records; replaying those"
    ) in result.stderr
    again = read_recording(replayed)
    assert not again.truncated and len(again) >= keep
    original, played = complete.blade("scalpel"), again.blade("scalpel")
    for name in ("q", "p", "state"):
        assert np.array_equal(original[name][:keep], played[name][:keep]), name
    assert np.array_equal(
        original["block"]["engine_force_N"][:keep], played["block"]["engine_force_N"][:keep]
    )
    # Nothing whole to play: refused, naming the file.
    empty = cut(path, tmp_path / "empty.rec", start + 10)
    result = run_servo(*args, "--device", f"scalpel=replay:{empty}")
    assert result.returncode == 4
    assert f"recording '{empty}' is truncated" in result.stderr
    assert "0 whole records" in result.stderr and "nothing to replay" in result.stderr


def test_an_older_record_version_is_refused_naming_both_versions(stroke, tmp_path):
    path, _ = stroke
    older = layout.RECORD_VERSION - 1
    data = path.read_bytes()
    current = f'"version":{layout.RECORD_VERSION}'.encode()
    assert data.count(current) == 1
    old = tmp_path / "old.rec"
    old.write_bytes(data.replace(current, f'"version":{older}'.encode()))
    with pytest.raises(RecordingError) as error:
        read_recording(old)
    assert f"record version {older}, this reader reads version {layout.RECORD_VERSION}" in str(
        error.value
    )
    result = run_servo(str(SPHERE), "--device", f"scalpel=replay:{old}")
    assert result.returncode == 4
    assert (
        f"recording '{old}': record version {older}, this servo reads version "
        f"{layout.RECORD_VERSION} only"
    ) in result.stderr


def test_a_recording_stopped_over_the_control_channel_is_complete(tmp_path):
    path = tmp_path / "live.rec"
    args = [str(SPHERE), "--device", "scalpel=sim:press-slide", "--engage"]
    with ServoProcess([*args, "--record-dir", str(tmp_path)]) as servo:
        client = connect(servo, ["scalpel"])
        client.record(path)
        while client.status()["recording"]["written"] < 200:
            time.sleep(0.01)
        reply = client.stop_recording()
        client.close()
    recording = read_recording(path)
    assert not recording.truncated
    assert len(recording) == reply["written"] >= 200
    assert recording.dropped_records == 0
    ticks = recording.ticks["tick"]
    assert np.array_equal(ticks, np.arange(ticks[0], ticks[0] + len(recording)))


def test_a_recording_killed_with_sigkill_is_truncated(tmp_path):
    path = tmp_path / "killed.rec"
    command = [servo_path(), str(SPHERE), "--device", "scalpel=sim:press-slide", "--engage"]
    process = subprocess.Popen(
        [*command, "--record", str(path)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    try:
        # Records reach the file in stdio blocks: wait for a hundred of them.
        while whole_records(path) < 100:
            assert process.poll() is None, process.stderr.read()
            time.sleep(0.01)
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait(30)
    assert process.returncode == -signal.SIGKILL
    killed = read_recording(path)
    assert killed.truncated and len(killed) >= 100
    assert f"{len(killed)} whole records" in killed.problem and str(path) in killed.problem
    ticks = killed.ticks["tick"]
    assert np.all(np.diff(ticks) > 0)
    # The same kill landing exactly on a record boundary is still told from a complete file.
    boundary = records_start(path) + len(killed) * killed.records.itemsize
    os.truncate(path, boundary)
    cut_at_boundary = read_recording(path)
    assert cut_at_boundary.truncated and cut_at_boundary.truncated_bytes == 0
    assert cut_at_boundary.records.tobytes() == killed.records.tobytes()


def test_a_recording_closed_by_sigterm_is_complete(tmp_path):
    path = tmp_path / "terminated.rec"
    args = [str(SPHERE), "--device", "scalpel=sim:press-slide", "--engage", "--record", str(path)]
    with ServoProcess(args) as servo:
        while whole_records(path) < 100:
            assert servo.process.poll() is None, servo.stderr_lines
            time.sleep(0.01)
        assert servo.stop() == 0  # SIGTERM: the force ramps down, the recording closes.
    recording = read_recording(path)
    assert not recording.truncated
    assert len(recording) == servo.stats()["recording"]["written"] >= 100
    # The stop ramp is recorded: the last ticks are flagged stopping.
    assert int(recording.ticks["servo_flags"][-1]) & 2


def test_the_trailer_counts_the_records_the_loop_dropped(tmp_path):
    """As fast as possible into the smallest ring (64 records) the writer, which drains every
    2 ms, falls behind: the trailer counts every tick that is not in the file."""
    path = tmp_path / "dropping.rec"
    stats = bake(SPHERE, path, "scalpel=sim:press-slide", extra=("--record-buffer-s", "0.001"))
    recording = read_recording(path)
    assert not recording.truncated
    assert recording.dropped_records == stats["dropped_records"] > 0
    assert len(recording) + recording.dropped_records == stats["ticks"]
    ticks = recording.ticks["tick"]
    gaps = int(np.sum(np.diff(ticks) - 1)) + int(ticks[0])
    assert gaps <= recording.dropped_records  # the rest were dropped after the last record


def test_what_is_not_a_regular_file_is_refused_without_waiting(tmp_path):
    fifo = tmp_path / "recording.fifo"
    os.mkfifo(fifo)  # No writer ever opens it: a blocking open would never return.
    for path in (fifo, "/dev/zero", tmp_path):
        with pytest.raises(RecordingError) as error:
            read_recording(path)
        assert str(error.value) == f"recording {str(path)!r}: not a regular file"
        result = run_servo(str(SPHERE), "--device", f"scalpel=replay:{path}", timeout_s=60)
        assert result.returncode == 4
        assert f"recording '{path}': not a regular file" in result.stderr
