"""The live timer's work per call is bounded by construction: at most MAX_DATAGRAMS
datagrams and BUDGET_S of draining, whatever is waiting. Its cost (p50, max) and the age of
the frame it keeps are printed (not asserted) while frames stream at 120 Hz with 50 and 500
points."""

import subprocess
import sys
import time

import bpy
import live_support
import numpy as np
import pytest

SCENE_WITH_POINTS = """
import dataclasses, sys
from hapticut.scenefile import load_scene, save_scene
scene = load_scene(sys.argv[1])
blades = [dataclasses.replace(b, points=int(sys.argv[3])) for b in scene.blades]
save_scene(dataclasses.replace(scene, blades=blades), sys.argv[2])
"""


@pytest.fixture(scope="module")
def finger(addon, tmp_path_factory):
    from addon.live import live_link

    scene = live_support.finger_with_stroke(tmp_path_factory.mktemp("live-finger"))
    yield scene
    live_link.stop()


@pytest.mark.parametrize("points", [50, 500])
def test_the_timer_is_bounded_while_frames_stream_at_120_hz(finger, tmp_path, points, monkeypatch):
    from addon.authoring import building
    from addon.live import live_link, live_session

    path = str(tmp_path / f"finger-{points}.hapticut.json")
    subprocess.run(
        [sys.executable, "-c", SCENE_WITH_POINTS, building.scene_file(finger), path, str(points)],
        check=True,
    )
    assert bpy.ops.hapticut.start_servo() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    session = live_link.current()
    live_session.run(session, path, ["Knife=viewport"], 1000.0)  # Streams at 120 Hz.
    live_support.follow(lambda: session.stream_frame is not None)
    assert len(session.stream_frame.blades["Knife"]["q"]) == points
    # At 120 Hz for 2 s.
    session.tick_costs_s.clear()
    session.stream_frame_ages_s.clear()
    began = time.perf_counter()
    while time.perf_counter() - began < 2.0:
        live_link.timer()
        time.sleep(1 / 120)
    costs = np.array(session.tick_costs_s) * 1e3
    ages = np.array(session.stream_frame_ages_s) * 1e3
    print(
        f"\n{points} points: timer call p50 {np.median(costs):.3f} ms, max {costs.max():.3f} ms "
        f"({len(costs)} calls); frame age at the timer p50 {np.median(ages):.2f} ms, "
        f"p99 {np.percentile(ages, 99):.2f} ms"
    )
    # A backlog: 1 s without a call leaves frames waiting (as many as the socket holds);
    # one call reads at most MAX_DATAGRAMS of them and keeps the newest it read.
    time.sleep(1.0)
    before = session.client.datagrams_read
    live_link.timer()
    read = session.client.datagrams_read - before
    assert 0 < read <= live_session.MAX_DATAGRAMS
    # With a bound of 4, the rest stay for later calls.
    monkeypatch.setattr(live_session, "MAX_DATAGRAMS", 4)
    time.sleep(0.5)
    before = session.client.datagrams_read
    live_link.timer()
    assert 0 < session.client.datagrams_read - before <= 4
    assert session.client.poll_all()
    live_link.stop()
