"""The live link inside Blender: one session (live_session), the timer that drains its stream
and sends the viewport poses, the draw handler, Simulate stroke and its bake.

No thread touches bpy: ``timer()`` runs on the main thread (bpy.app.timers; the tests call it
themselves, timers do not run in background mode). ``shutdown()`` (unregister, loading
another file) stops the servo and removes the timer and the draw handler.
"""

from __future__ import annotations

import os
import time

import bpy
from bpy.app.handlers import persistent

from . import (
    baking,
    building,
    device_list,
    live_draw,
    live_session,
    preferences,
    stroke_path,
    toolkit,
    toolkit_link,
    undo_steps,
    work_folder,
)
from .exchange import scene_objects
from .units import mm_per_unit

TIMER_INTERVAL_S = 1.0 / 120.0

_session: live_session.Session | None = None
_scene_name = ""
_last_error = ""
# Figures of the last Simulate stroke (for the measurements).
last_simulate: dict = {}


def current() -> live_session.Session | None:
    return _session


def last_error() -> str:
    return _session.error if _session is not None and _session.error else _last_error


def _scene():
    return bpy.data.scenes.get(_scene_name) if _scene_name else None


def link(context=None, timeout_s: float = toolkit.QUICK_TIMEOUT_S):
    try:
        return toolkit_link.link(preferences.executable(context), timeout_s=timeout_s)
    except toolkit.ToolkitError as error:
        raise live_session.SessionError(str(error)) from None


def log_path(scene) -> str:
    return os.path.join(work_folder.work_directory(scene), "servo.log")


def start(context) -> live_session.Session:
    """Start the servo (stopping an earlier one); SessionError for the panel."""
    global _session, _scene_name, _last_error
    scene = context.scene
    live = scene.hapticut_live
    if _session is not None:
        stop()
    _last_error = ""
    try:
        modules = link(context)
        path = log_path(scene)
        # Recordings (Record, Simulate Stroke) go to the scene's work folder only.
        work = work_folder.work_directory(scene)
        _session = live_session.start(
            modules, path, port=live.port, realtime=live.realtime, extra=("--record-dir", work)
        )
    except live_session.SessionError as error:
        _last_error = live.error = str(error)
        raise
    live.log_path, live.error = path, ""
    _scene_name = scene.name
    _register()
    return _session


def refresh_devices(context, rate_Hz: float | None = None) -> dict:
    """*Refresh devices*: run the servo's listing at rate_Hz (the panel's rate), its
    stiffness limits at that rate; the panel shows a failure (SessionError). Everything it
    waits for (asking the toolkit for its servo the first time, then the listing) is
    bounded by device_list.LIST_TIMEOUT_S together."""
    live = context.scene.hapticut_live
    rate_Hz = live.rate_Hz if rate_Hz is None else rate_Hz
    deadline = time.monotonic() + device_list.LIST_TIMEOUT_S
    try:
        servo = link(context, timeout_s=device_list.LIST_TIMEOUT_S).servo
        listing = device_list.refresh(servo, max(0.1, deadline - time.monotonic()), rate_Hz)
    except (live_session.SessionError, device_list.DeviceListError) as error:
        live.device_error = f"devices not listed: {error}"
        raise live_session.SessionError(live.device_error) from None
    live.device_error = ""
    return listing


def devices(scene) -> list[str]:
    """The ``--device`` texts of the scene's blades (NAME=BINDING) for the panel's choice."""
    live = scene.hapticut_live
    chosen = device_list.binding(live.device_choice, live.bridge_port, live.custom_device)
    return [f"{obj.name}={chosen or obj.hapticut.device}" for obj in scene_objects(scene, "BLADE")]


def blade_springs(scene, name: str = "") -> int:
    """The point springs the blade called name renders together (device_list.blade_springs);
    without a name, the most of any blade of the scene (one device choice binds them all)."""
    blades = [o for o in scene_objects(scene, "BLADE") if not name or o.name == name]
    settings = [o.hapticut for o in blades]
    springs = [device_list.blade_springs(s.blade_points, s.blade_coupling) for s in settings]
    return max(springs, default=1)


def check_limits(context, bindings: list[str], settings: dict, rate_Hz: float = 1000.0) -> None:
    """Refuse settings above a bound device's limits at the servo's rate (SessionError naming
    blade, device and limit); the listing is read first if it was not yet, or again if the
    kept one's stiffness limits are for another rate (the servo's rule, not the add-on's)."""
    if not settings:
        return
    listing = device_list.cached()
    if listing is None or device_list.listed_rate() != float(rate_Hz):
        listing = refresh_devices(context, rate_Hz)
    problems = []
    for text in bindings:
        name, _, device = text.partition("=")
        limits = device_list.limits_for(listing, device)
        springs = blade_springs(context.scene, name)
        found = device_list.settings_problems(settings, limits, rate_Hz, springs)
        problems += [f"{name} ({device}): {problem}" for problem in found]
    if problems:
        raise live_session.SessionError("; ".join(problems) + " (lower it in the panel)")


def requested_settings(live) -> dict:
    settings = {}
    if live.stiffness_N_per_mm > 0:
        settings["stiffness_N_per_mm"] = live.stiffness_N_per_mm
    if live.max_force_N > 0:
        settings["max_force_N"] = live.max_force_N
    if live.max_torque_N_mm > 0:
        settings["max_torque_N_mm"] = live.max_torque_N_mm
    return settings


def _built_scene(scene) -> tuple[str, str]:
    path = building.scene_file(scene)
    if path is None:
        raise live_session.SessionError("no scene built yet: Tetrahedralize first")
    preview = os.path.join(os.path.dirname(path), building.PREVIEW_FILE)
    return path, preview


def _ensure_session(context) -> live_session.Session:
    if _session is None or not _session.alive:
        return start(context)
    return _session


def go_live(context) -> None:
    """Start (if needed) and run the scene with the panel's devices and settings."""
    scene = context.scene
    live = scene.hapticut_live
    bindings, settings = devices(scene), requested_settings(live)
    try:
        check_limits(context, bindings, settings, live.rate_Hz)
    except live_session.SessionError as error:
        live.error = str(error)
        raise
    session = _ensure_session(context)
    path, preview = _built_scene(scene)
    try:
        live_session.run(session, path, bindings, live.rate_Hz, settings=settings)
    except live_session.SessionError as error:
        live.error = str(error)
        raise
    session.preview_path = live.preview_path = preview
    live.error = ""
    if live.force_shading:  # The servo may refuse it (docs/protocol.md): say why, run on.
        try:
            live_session.request(session, "set_parameters", shading=True)
        except live_session.SessionError as error:
            live.error = f"force shading not applied: {error}"


def engage(engaged: bool) -> None:
    if _session is None:
        raise live_session.SessionError("no servo: Start it first")
    live_session.request(_session, "engage", engaged)


def record_live(scene) -> str:
    """Toggle recording of the live run; the path while recording, "" once stopped."""
    session = _session
    if session is None or not session.running:
        raise live_session.SessionError("nothing runs: Go live first")
    live = scene.hapticut_live
    if session.status.get("recording", {}).get("active"):
        live_session.request(session, "stop_recording")
        session.status = live_session.request(session, "status")
        live.recording_path = session.recording_path
        return ""
    folder = os.path.join(work_folder.work_directory(scene), "recordings")
    path = os.path.join(folder, time.strftime("live-%Y%m%d-%H%M%S.rec"))
    os.makedirs(folder, exist_ok=True)
    live_session.request(session, "record", path)
    session.recording_path = path
    session.status = live_session.request(session, "status")
    return path


def simulate(context) -> dict:
    """Sample every blade's animation into a sim path and run it as fast as possible,
    recording; the timer bakes it when the servo is done."""
    scene = context.scene
    live = scene.hapticut_live
    began = time.perf_counter()
    path, preview = _built_scene(scene)
    blades = scene_objects(scene, "BLADE")
    folder = os.path.join(work_folder.work_directory(scene), "stroke")
    bindings = []
    for obj in blades:
        poses = stroke_path.sample_poses(scene, obj, live.rate_Hz)
        file = stroke_path.write_path(poses, os.path.join(folder, f"{obj.name}.path.json"))
        if "," in file or "=" in obj.name:
            raise live_session.SessionError(f"{obj.name}: the path {file} cannot hold ',' ")
        hand = 1 if live.simulated_hand else 0
        bindings.append(f"{obj.name}=sim:{file},hand={hand},hold_s=0")
    sampled = time.perf_counter()
    check_limits(context, bindings, requested_settings(live), live.rate_Hz)
    session = _ensure_session(context)
    record = os.path.join(folder, "stroke.rec")
    live_session.run(
        session,
        path,
        bindings,
        live.rate_Hz,
        as_fast_as_possible=True,
        record_path=record,
        settings=requested_settings(live),
        engage=True,
    )
    session.preview_path = live.preview_path = preview
    session.simulate = {
        "began": began,
        "sampled_s": sampled - began,
        "record": record,
        "scene": scene.name,
        "bake": live.bake_after_simulate,
    }
    return session.simulate


def _finish_simulate(session) -> None:
    """The stroke is done (the servo stopped by itself, the recording is closed): bake."""
    global last_simulate
    job, session.simulate = session.simulate, None
    session.state = "connected"
    scene = bpy.data.scenes.get(job["scene"])
    figures = {
        "servo_s": time.perf_counter() - job["began"] - job["sampled_s"],
        "sampled_s": job["sampled_s"],
    }
    if scene is None:
        return
    scene.hapticut_live.recording_path = job["record"]
    if job["bake"]:
        try:
            baked = baking.bake(scene, session.link, job["record"], session.preview_path)
            figures["bake_s"] = baked["seconds"]
            undo_steps.push("Bake stroke")
        except baking.BakeError as error:
            scene.hapticut_live.error = str(error)
    figures["total_s"] = time.perf_counter() - job["began"]
    figures["ticks"] = session.status.get("ticks", 0)
    last_simulate = figures


def viewport_poses(scene) -> dict[str, list[float]]:
    """The world pose (mm, quaternion) of every blade driven by a viewport device."""
    session = _session
    if session is None:
        return {}
    mm = mm_per_unit(scene)
    poses = {}
    for blade in session.blades:
        if blade.get("kind") != "viewport":
            continue
        obj = scene.objects.get(blade["name"])
        if obj is not None:
            poses[blade["name"]] = stroke_path.pose_of(obj.matrix_world, mm)
    return poses


def timer():
    """bpy.app.timers callback: the session's tick; the next interval, None once stopped."""
    session = _session
    if session is None:
        return None
    scene = _scene()
    try:
        poses = viewport_poses(scene) if scene is not None and session.running else {}
        if session.simulate is not None:
            session.last_status_s = 0.0  # Follow the stroke closely.
        if live_session.tick(session, poses):
            live_draw.invalidate()
        if session.simulate is not None and session.status.get("state") == "stopped":
            _finish_simulate(session)
    except Exception as error:  # Never a traceback out of a timer: the panel says it.
        session.error = f"{type(error).__name__}: {error}"
    live_draw.tag_redraw()
    return TIMER_INTERVAL_S if session.alive else None


def _register() -> None:
    if not bpy.app.timers.is_registered(timer):
        bpy.app.timers.register(timer, first_interval=TIMER_INTERVAL_S)
    live_draw.add_handler()


def timer_registered() -> bool:
    return bpy.app.timers.is_registered(timer)


def stop() -> None:
    """Stop the servo; remove the timer and the draw handler."""
    global _session
    session, _session = _session, None
    if session is not None:
        live_session.stop(session)
    if bpy.app.timers.is_registered(timer):
        bpy.app.timers.unregister(timer)
    live_draw.remove_handler()


def shutdown() -> None:
    stop()


@persistent
def _on_load_pre(*_args) -> None:
    stop()


def add_handlers() -> None:
    if _on_load_pre not in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.append(_on_load_pre)


def remove_handlers() -> None:
    if _on_load_pre in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(_on_load_pre)
