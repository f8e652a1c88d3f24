"""The scene's cut tets through the servo (docs/protocol.md, "Cut tets"): recorded with
every tick and rebuilt by a replay, streamed to clients that rebuild the set (and ask for
what they missed), reset, saved and loaded over the control channel. The real servo binary
over loopback, a sim stroke through flesh."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest
from hapticut.servo_client import CutSet, ServoError
from servo_test_support import (
    ServoProcess,
    bake,
    connect,
    offline_check,
    read_recording,
    tissue_scene,
)


def replay(scene, recorded, into):
    bake(scene, into, f"scalpel=replay:{recorded}")
    return read_recording(into)


def assert_cut_blocks_replayed(a, b) -> None:
    """Every record's cut block again, bit for bit, but for the generation: a count of the
    servo process's resets and loads, which changes at the same records."""
    n = len(a)
    assert len(b) >= n
    recorded, replayed = a.cut_blocks.copy(), b.cut_blocks[:n].copy()
    for blocks in (recorded, replayed):
        changed = np.diff(blocks["generation"].astype(np.int64)) != 0
        blocks["generation"] = np.concatenate([[0], np.cumsum(changed)])
    assert recorded.tobytes() == replayed.tobytes()


def test_a_recording_carries_the_engines_cut_order_and_a_replay_rebuilds_it(tmp_path):
    scene = tissue_scene(tmp_path / "tissue.hapticut.json")
    bake(scene, tmp_path / "a.rec", "scalpel=sim")
    a = read_recording(tmp_path / "a.rec")
    blocks = a.cut_blocks
    order = a.cut_order()
    assert len(order) > 50 and len(set(order.tolist())) == len(order)
    assert int(blocks["before_tick"][0]) == 0 and (np.diff(blocks["total"].astype(int)) >= 0).all()
    # Halfway through the cutting, the order is the start of the whole one.
    half = a.cut_order(int(np.argmax(blocks["total"] >= len(order) // 2)))
    assert 0 < len(half) < len(order) and np.array_equal(half, order[: len(half)])
    # The engine stepped offline through the same poses cuts the same tets, tick by tick.
    assert offline_check(scene, a, "scalpel") > 0
    b = replay(scene, tmp_path / "a.rec", tmp_path / "b.rec")
    assert_cut_blocks_replayed(a, b)


# The sim stroke's ticks (it then holds still): a run is stopped after them.
STROKE_TICKS = 1000


def wait_for_stroke(client) -> None:
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and client.status()["ticks"] < STROKE_TICKS:
        time.sleep(0.01)
    client.stop()


def run_recorded(client, path, until=None) -> None:
    client.record(path)
    client.start()
    if until is not None:
        until()
    wait_for_stroke(client)


@pytest.mark.serial
def test_the_stream_carries_the_cuts_and_a_client_that_misses_frames_asks_for_the_rest(
    tmp_path,
):
    scene = tissue_scene(tmp_path / "tissue.hapticut.json")
    args = [str(scene), "--device", "scalpel=sim", "--wait", "--engage", "--record-dir"]
    with ServoProcess([*args, str(tmp_path)]) as servo:
        every, sparse = connect(servo, ["scalpel"]), connect(servo, ["scalpel"])
        every.subscribe(rate_Hz=250)
        sparse.subscribe(rate_Hz=5)
        every_set, sparse_set = CutSet(), CutSet()
        sparse_whole = []
        every.record("run.rec")
        every.start()
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and every.status()["ticks"] < STROKE_TICKS:
            for frame in every.poll_all():
                every_set.take(frame, every)
            frame = sparse.poll_newest()
            if frame is not None:
                sparse_whole.append(sparse_set.take(frame, sparse))
            time.sleep(0.005)
        every.stop()
        for frame in every.poll_all():
            every_set.take(frame, every)
        generation, whole = every.cuts()
        assert servo.stop() == 0
    recorded = read_recording(tmp_path / "run.rec").cut_order()
    assert len(whole) > 50 and np.array_equal(whole, recorded)
    # Every frame taken: the order, appended a frame at a time, up to the last frame's tick.
    assert every_set.generation == generation and every_set.total > 50
    assert every_set.order == whole[: every_set.total].tolist()
    # A 5 Hz subscriber misses most of what the frames carried: it asked for the rest, and
    # was whole at every frame.
    assert sparse_whole and all(sparse_whole) and sparse_set.fills > 0
    assert sparse_set.order == whole[: len(sparse_set.order)].tolist()


def test_cuts_are_saved_reset_and_loaded_and_a_run_from_loaded_cuts_replays(tmp_path):
    scene = tissue_scene(tmp_path / "tissue.hapticut.json")
    args = [str(scene), "--device", "scalpel=sim", "--wait", "--engage", "--as-fast-as-possible"]
    with ServoProcess([*args, "--record-dir", str(tmp_path)]) as servo:
        client = connect(servo, ["scalpel"])
        run_recorded(client, "first.rec")
        _, cut = client.cuts()
        assert len(cut) > 50
        saved = client.save_cuts("cuts.json")
        assert saved["tets"] == len(cut)
        document = json.loads((tmp_path / "cuts.json").read_text())
        assert document["format"] == "hapticut.cuts" and document["tets"] == cut.tolist()
        with pytest.raises(ServoError, match="already exists"):
            client.save_cuts("cuts.json")

        before = client.cuts()[0]
        assert client.reset_cuts()["at"] == "now"
        generation, empty = client.cuts()
        assert generation != before and len(empty) == 0

        # Refusals name the file and what is wrong, and leave the cuts as they are.
        (tmp_path / "other.json").write_text(json.dumps({**document, "tet_count": 7}))
        with pytest.raises(ServoError, match=r"saved from a scene of 7 tets"):
            client.load_cuts("other.json")
        (tmp_path / "twice.json").write_text(
            json.dumps({**document, "tets": [*document["tets"], document["tets"][0]]})
        )
        with pytest.raises(ServoError, match=rf"tets/{len(cut)}: tet \d+ is given twice"):
            client.load_cuts("twice.json")
        with pytest.raises(ServoError, match="may not hold"):
            client.load_cuts("../cuts.json")
        with pytest.raises(ServoError, match="outside the recording directory"):
            client.load_cuts("/etc/passwd")
        assert len(client.cuts()[1]) == 0

        loaded = client.load_cuts("cuts.json")
        assert loaded["tets"] == len(cut)
        assert np.array_equal(client.cuts()[1], cut)
        # A second run starts from the loaded cuts; it cannot load others while it runs.
        client.record("second.rec")
        client.start()
        with pytest.raises(ServoError, match="a run is on"):
            client.load_cuts("cuts.json")
        wait_for_stroke(client)
        assert servo.stop() == 0
    second = read_recording(tmp_path / "second.rec")
    assert int(second.cut_blocks["before_tick"][0]) == len(cut)
    assert np.array_equal(second.cut_order(0)[: len(cut)], cut)
    # The same stroke again through its own cut: the tets it cut were cut already.
    assert len(second.cut_order()) == len(cut)
    assert offline_check(scene, second, "scalpel") > 0
    replayed = replay(scene, tmp_path / "second.rec", tmp_path / "replayed.rec")
    assert_cut_blocks_replayed(second, replayed)


@pytest.mark.serial
def test_a_reset_during_a_run_comes_before_a_tick_and_its_replay_repeats_it(tmp_path):
    scene = tissue_scene(tmp_path / "tissue.hapticut.json")
    args = [str(scene), "--device", "scalpel=sim", "--wait", "--engage"]
    with ServoProcess([*args, "--record-dir", str(tmp_path)]) as servo:
        client = connect(servo, ["scalpel"])

        def reset_once_cutting() -> None:
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline and len(client.cuts()[1]) < 20:
                time.sleep(0.005)
            assert client.reset_cuts()["at"] == "the next tick"

        run_recorded(client, "reset.rec", reset_once_cutting)
        assert servo.stop() == 0
    recorded = read_recording(tmp_path / "reset.rec")
    blocks = recorded.cut_blocks
    changes = np.flatnonzero(np.diff(blocks["generation"].astype(np.int64)) != 0) + 1
    assert len(changes) == 1
    assert int(blocks["before_tick"][changes[0]]) == 0
    assert int(blocks["total"][changes[0] - 1]) >= 20
    replayed = replay(scene, tmp_path / "reset.rec", tmp_path / "replayed.rec")
    assert_cut_blocks_replayed(recorded, replayed)
