"""The draw handler's own code with the real servo streaming: a batch built once per new frame
and reused by every redraw in between, the arrays drawn being the frame's, the age of each
drawn frame recorded and shown in the panel.

Background mode has no GPU ("GPU functions for drawing are not available in background mode"),
so ``gpu`` and ``gpu_extras.batch`` are replaced by a recorder: the one part here that cannot
exist. Everything on this side of it (live_draw.draw, its cache, the ages, the panel) is the
add-on's real code, called as Blender calls it: after each timer run that tagged a redraw."""

import sys
import time
import types

import bpy
import live_support
import numpy as np
import pytest


class RecordingShader:
    def __init__(self):
        self.colours = []

    def uniform_float(self, name, value):
        assert name == "color"
        self.colours.append(tuple(value))


class RecordingBatch:
    def __init__(self, kind, attributes, log):
        self.kind = kind
        self.pos = np.asarray(attributes["pos"])
        self.log = log

    def draw(self, shader):
        self.log.append((self.kind, len(self.pos)))


@pytest.fixture()
def recording_gpu(monkeypatch):
    """A stand-in for Blender's gpu module: records shaders, batches and draw calls."""
    log = {"shaders": [], "batches": [], "draws": [], "state": []}

    def from_builtin(name):
        assert name == "UNIFORM_COLOR"
        shader = RecordingShader()
        log["shaders"].append(shader)
        return shader

    def batch_for_shader(shader, kind, attributes):
        batch = RecordingBatch(kind, attributes, log["draws"])
        log["batches"].append(batch)
        return batch

    gpu = types.ModuleType("gpu")
    gpu.shader = types.SimpleNamespace(from_builtin=from_builtin)
    gpu.state = types.SimpleNamespace(
        point_size_set=lambda size: log["state"].append(("point", size)),
        line_width_set=lambda width: log["state"].append(("line", width)),
    )
    extras = types.ModuleType("gpu_extras")
    batch_module = types.ModuleType("gpu_extras.batch")
    batch_module.batch_for_shader = batch_for_shader
    extras.batch = batch_module
    monkeypatch.setitem(sys.modules, "gpu", gpu)
    monkeypatch.setitem(sys.modules, "gpu_extras", extras)
    monkeypatch.setitem(sys.modules, "gpu_extras.batch", batch_module)
    return log


@pytest.fixture()
def finger(addon, tmp_path_factory):
    from addon.live import live_link

    scene = live_support.finger_with_stroke(tmp_path_factory.mktemp("live-finger"))
    yield scene
    live_link.stop()


def test_draw_builds_once_per_frame_draws_the_frame_and_records_its_age(finger, recording_gpu):
    from addon.live import live_draw, live_link, live_session
    from addon.ui import live_panels

    assert bpy.ops.hapticut.start_servo() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert bpy.ops.hapticut.go_live() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    session = live_link.current()
    live_support.follow(
        lambda: session.stream_frame is not None and session.status.get("ticks", 0) > 50
    )
    live_draw.invalidate()
    builds0, draws0, drawn0 = live_draw.builds, live_draw.draws, session.stream_frames_drawn
    sequences = set()
    began = time.perf_counter()
    while time.perf_counter() - began < 1.0:
        live_link.timer()  # Takes the newest frame and tags a redraw, as bpy.app.timers runs it.
        live_draw.draw(live_link.current)  # The redraw that follows.
        sequences.add(session.stream_frame.sequence)
        # A second redraw of the same frame (another view, an overlay).
        live_draw.draw(live_link.current)
        time.sleep(0.004)
    builds = live_draw.builds - builds0
    # One build per new frame drawn, none for a redraw of a frame already built.
    assert builds == len(sequences) == session.stream_frames_drawn - drawn0
    assert builds > 20, builds  # Frames stream at 120 Hz: about 100 in the second.
    assert len(recording_gpu["draws"]) == 5 * (live_draw.draws - draws0)
    # Every draw: the five batches of the newest build, in the add-on's colours.
    newest = recording_gpu["batches"][-5:]
    assert [b.kind for b in newest] == ["POINTS", "POINTS", "LINES", "LINES", "LINES"]
    geometry = live_draw.stream_frame_geometry(
        session.stream_frame, live_draw.mm_per_unit(finger), finger.objects
    )
    points = len(session.stream_frame.blades["Knife"]["q"])
    assert np.array_equal(newest[0].pos, geometry["proxies"]) and len(newest[0].pos) == points
    assert np.array_equal(newest[1].pos, geometry["devices"])
    assert len(newest[2].pos) == 2 * points and len(newest[3].pos) == 2
    # The knife object's edges at the frame's ideal pose.
    knife = bpy.data.objects["Knife"]
    assert np.array_equal(newest[4].pos, geometry["knife"])
    assert len(newest[4].pos) == 2 * len(knife.data.edges) > 0
    assert recording_gpu["shaders"][-1].colours[-5:] == [
        live_draw.PROXY_COLOUR,
        live_draw.DEVICE_COLOUR,
        live_draw.DEVICE_COLOUR,
        live_draw.FORCE_COLOUR,
        live_draw.KNIFE_COLOUR,
    ]
    # The age of each drawn frame: servo time to its first draw, never before the timer took it.
    drawn = session.drawn_ages_s[-builds:]
    assert len(drawn) == builds and min(drawn) >= 0 and max(drawn) < 1.0
    age_line = next(
        line
        for line in live_panels.status_lines(session)
        if line.startswith("frame age p50 / p99: ")
    )
    assert age_line.endswith(" drawn")
    print(
        f"\nframe age p50 / p99 at the timer {live_session.age_text(session.stream_frame_ages_s)}, "
        f"at the draw handler {live_session.age_text(drawn)} ({builds} frames drawn in 1 s; "
        "the handler called right after each timer run, with the GPU recorded: no viewport "
        "redraw delay is in it)"
    )
    assert bpy.ops.hapticut.stop_servo() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert not live_draw.handler_added()
