"""The session panel with the real servo over loopback: Start, Go Live, status, Stop; a busy
port and a missing toolkit said plainly; the servo killed mid-session shows as lost and Start
recovers; unregister and loading another file leave no timer, handler or process."""

import json
import os
import signal
import socket

import bpy
import live_support
import numpy as np
import pytest


@pytest.fixture()
def finger(addon, tmp_path_factory):
    from addon.live import live_link

    scene = live_support.finger_with_stroke(tmp_path_factory.mktemp("live-finger"))
    yield scene
    live_link.stop()


def alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as file:
            return file.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_start_go_live_status_and_stop(finger):
    from addon.live import live_draw, live_link
    from addon.ui import live_panels

    assert live_panels.status_lines(None)[0].startswith("not connected")
    assert bpy.ops.hapticut.start_servo() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    session = live_link.current()
    assert session is not None and live_link.timer_registered() and live_draw.handler_added()
    assert os.path.isfile(finger.hapticut_live.log_path)
    assert bpy.ops.hapticut.go_live() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert [b["kind"] for b in session.blades] == ["viewport"]
    live_support.follow(
        lambda: session.stream_frame is not None and session.status.get("ticks", 0) > 50
    )
    lines = live_panels.status_lines(session)
    assert lines[0] == "connected (running), servo running"
    assert any(line.startswith("Knife (viewport, fresh)") for line in lines)
    assert any(line.startswith("Knife: TET") for line in lines)
    # The frames' age where the timer took them (headless, no viewport draws: the age at draw
    # joins this line in a GUI, and test_live_draw.py drives the draw handler itself).
    age_line = next(line for line in lines if line.startswith("frame age p50 / p99: "))
    p50_ms, p99_ms = (float(x) for x in age_line.split(": ")[1].split(" ms")[0].split(" / "))
    assert 0 <= p50_ms <= p99_ms and "drawn" not in age_line
    # What the draw handler draws (its batches are made from these arrays, in Blender units).
    geometry = live_draw.stream_frame_geometry(session.stream_frame, 0.5)
    q = session.stream_frame.blades["Knife"]["q"]
    assert geometry["proxies"].shape == (len(q), 3) and geometry["lines"].shape == (2 * len(q), 3)
    assert np.allclose(geometry["proxies"], q / 0.5, atol=1e-4)
    assert geometry["force"].shape == (2, 3)
    assert bpy.ops.hapticut.engage_servo(engaged=True) == {"FINISHED"}
    live_support.follow(lambda: session.status.get("engaged") is True)
    pid = session.process.pid
    assert bpy.ops.hapticut.stop_servo() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert live_link.current() is None and not live_link.timer_registered()
    assert not live_draw.handler_added()
    assert not alive(pid)
    # The log the panel links to holds the servo's own lines.
    with open(finger.hapticut_live.log_path) as log:
        assert "hapticut-servo: loaded" in log.read()
    assert bpy.ops.hapticut.open_servo_log() == {"FINISHED"}
    assert "control: 127.0.0.1:" in bpy.data.texts["hapticut-servo.log"].as_string()


def test_a_busy_port_is_said_so(finger):
    from addon.live import live_link
    from addon.ui import live_panels

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        finger.hapticut_live.port = taken.getsockname()[1]
        try:
            with pytest.raises(RuntimeError, match="busy"):
                bpy.ops.hapticut.start_servo()
                bpy.ops.hapticut.wait()
        finally:
            finger.hapticut_live.port = 0
    assert live_link.current() is None
    assert "busy" in finger.hapticut_live.error
    assert "busy" in live_panels.status_lines(None)[0]


def test_a_missing_toolkit_names_the_install_command(finger):
    from addon.live import live_link
    from addon.toolkit import runner, toolkit_link

    prefs = bpy.context.preferences.addons["addon"].preferences
    saved = prefs.toolkit_path
    prefs.toolkit_path = "/nonexistent/hapticut"
    toolkit_link._link = None
    try:
        with pytest.raises(RuntimeError, match="install"):
            bpy.ops.hapticut.start_servo()
            bpy.ops.hapticut.wait()
        assert runner.INSTALL_COMMAND in finger.hapticut_live.error
        assert live_link.current() is None
    finally:
        prefs.toolkit_path = saved


def test_the_servo_killed_mid_session_shows_as_lost_and_start_recovers(finger):
    from addon.live import live_link
    from addon.ui import live_panels

    assert bpy.ops.hapticut.go_live() == {"FINISHED"}  # Starts the servo too.
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    session = live_link.current()
    live_support.follow(lambda: session.stream_frame is not None)
    os.kill(session.process.pid, signal.SIGKILL)
    session.process.wait(10)
    assert live_link.timer() is None  # The timer ends itself; no exception.
    assert session.state == "lost"
    lines = live_panels.status_lines(session)
    assert lines[0].startswith("servo lost: the servo exited (code -9)")
    assert lines[1] == "Start to recover"
    assert bpy.ops.hapticut.start_servo() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert bpy.ops.hapticut.go_live() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    recovered = live_link.current()
    assert recovered is not session and recovered.alive
    live_support.follow(lambda: recovered.stream_frame is not None)


def test_unregister_and_loading_a_file_remove_timer_handler_and_servo(finger, tmp_path):
    import blender_scene

    from addon.live import live_draw, live_link

    path = str(tmp_path / "live_link.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    assert bpy.ops.hapticut.start_servo() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    pid = live_link.current().process.pid
    bpy.ops.wm.open_mainfile(filepath=path)  # Loading another file stops everything.
    assert live_link.current() is None and not live_link.timer_registered()
    assert not live_draw.handler_added() and not alive(pid)
    assert bpy.ops.hapticut.start_servo() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    pid = live_link.current().process.pid
    blender_scene.disable_addon()
    try:
        assert live_link.current() is None and not live_link.timer_registered()
        assert not live_draw.handler_added() and not alive(pid)
    finally:
        blender_scene.enable_addon()


def test_the_client_is_the_installed_toolkits_own(finger):
    import json
    import subprocess

    import blender_scene

    from addon.live import live_link

    found = json.loads(
        subprocess.run(
            [blender_scene.toolkit_executable(), "paths", "--json"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    )
    link = live_link.link()
    assert sorted(link.modules) == sorted(
        ("servo_client", "recording", "servo_layout", "cut_surface")
    )
    for module in link.modules.values():
        assert os.path.dirname(module.__file__) == found["package"]
    assert link.servo == found["servo"]


def test_force_shading_asked_for_is_applied_by_the_servo(finger):
    from addon.live import live_link, live_session

    finger.hapticut_live.force_shading = True
    assert bpy.ops.hapticut.go_live() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert finger.hapticut_live.error == ""
    session = live_link.current()
    live_support.follow(lambda: session.stream_frame is not None)
    assert live_session.request(session, "status")["settings"]["shading"] is True


def test_the_live_panels_draw_in_every_state(finger):
    from test_addon_panels import CheckingLayout, draw

    from addon.live import live_link
    from addon.ui import live_panels

    def texts() -> list[str]:
        drawn = []
        for panel_class in (live_panels.HAPTICUT_PT_live, live_panels.HAPTICUT_PT_bake):
            layout = CheckingLayout()
            draw(panel_class, layout)
            drawn += layout.texts
        return drawn

    for mode in ("VIEWPORT", "CUSTOM"):
        finger.hapticut_live.device_mode = mode
        assert "not connected" in texts()
    finger.hapticut_live.device_mode = "VIEWPORT"
    assert bpy.ops.hapticut.go_live() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    session = live_link.current()
    live_support.follow(lambda: session.stream_frame is not None and session.status.get("blades"))
    assert any(text.startswith("connected (running)") for text in texts())
    finger.hapticut_live.bake_report = json.dumps(
        {
            "frames": 3,
            "ticks": 100,
            "seconds": 0.1,
            "blades": {"Knife": {"cut_faces": 4, "max_force_N": 1.0}},
        }
    )
    assert "Knife: 4 cut faces, max force 1.00 N" in texts()
    os.kill(session.process.pid, signal.SIGKILL)
    session.process.wait(10)
    live_link.timer()
    assert "Start to recover" in texts()


def test_a_hid_profile_chosen_with_no_such_device_connected_says_so(finger):
    from addon.live import device_list, live_link
    from addon.ui import live_panels

    assert bpy.ops.hapticut.refresh_devices() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    listing = device_list.cached()
    absent = next(
        p["name"]
        for p in listing["profiles"]
        if not any(d["profile"] == p["name"] for d in listing["devices"])
    )
    finger.hapticut_live.device_mode = f"HID:{absent}"
    try:
        with pytest.raises(RuntimeError, match=f"no device matches profile '{absent}'"):
            bpy.ops.hapticut.go_live()
            bpy.ops.hapticut.wait()
        assert f"device 'Knife=hid:{absent}'" in finger.hapticut_live.error
        # The servo stays up and says nothing is running; another device runs at once.
        session = live_link.current()
        assert session is not None and session.alive
        assert live_panels.status_lines(session)[0].startswith("connected")
        finger.hapticut_live.device_mode = "VIEWPORT"
        assert bpy.ops.hapticut.go_live() == {"FINISHED"}
        assert bpy.ops.hapticut.wait() == {"FINISHED"}
        assert [b["kind"] for b in live_link.current().blades] == ["viewport"]
    finally:
        finger.hapticut_live.device_mode = "VIEWPORT"


def test_the_live_cut_region_is_the_servos_cut_and_reset_cuts_clears_it(finger):
    """The knife moved down through the skin and flesh by its keyframes while live: the cut
    region object is the skin of the tets the servo cut (its cut set, as the stream and the
    cuts replies carried it), the panel counts them, and Reset Cuts empties it."""
    from addon.live import live_cut, live_link, live_session
    from addon.ui import live_panels

    assert bpy.ops.hapticut.start_servo() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    session = live_link.current()
    assert bpy.ops.hapticut.go_live() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    for frame in range(finger.frame_start, finger.frame_end + 1):
        finger.frame_set(frame)
        ticks = session.status.get("ticks", 0)
        live_support.follow(lambda t=ticks: session.status.get("ticks", 0) > t + 20)
    generation, order = live_session.request(session, "cuts")
    assert len(order) > 10
    # The stream's set catches up with the servo's (a frame past the last cut, its holes
    # filled by cuts replies).
    live_support.follow(
        lambda: (
            session.cut_set.generation == generation
            and len(session.cut_set.order) >= len(order)
            and session.cut_set.wanted_from() is None
        )
    )
    assert session.cut_set.order[: len(order)] == order.tolist()
    live_cut.update(finger, session, force=True)
    tets = session.link.preview_tets(session.preview_path)
    expected = live_cut.boundary_faces(tets["tets"], session.cut_set.order)
    assert live_cut.face_count() == len(expected) > 0
    obj = bpy.data.objects[live_cut.OBJECT]
    assert obj.hide_render and obj.name in bpy.data.collections[live_cut.COLLECTION].objects
    assert f"cut: {len(session.cut_set.order):,} tets" in "\n".join(
        live_panels.status_lines(session)
    )
    assert bpy.ops.hapticut.reset_cuts() == {"FINISHED"}
    live_support.follow(
        lambda: session.cut_set.generation != generation and not session.cut_set.order
    )
    live_cut.update(finger, session, force=True)
    assert live_cut.face_count() == 0
