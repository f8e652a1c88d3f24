"""The live link inside Blender: one session (live_session), the timer that drains its stream
and sends the viewport poses, the draw handler (Simulate stroke, above this and the bake:
``simulate.py``).

Starting the servo, Go Live and Simulate Stroke wait on other processes: they are steps
(``steps.py``) run as the add-on's job (``jobs.py``), and ``*_steps`` names them here.
No thread touches bpy: ``timer()`` runs on the main thread (bpy.app.timers; the tests call it
themselves, timers do not run in background mode). ``stop()`` (unregister, loading another
file) stops the servo and removes the timer and the draw handler.
"""

from __future__ import annotations

import os
import time

import bpy
from bpy.app.handlers import persistent

from ..authoring import building, recording_stamp, work_folder
from ..authoring.exchange import scene_objects
from ..background import jobs, steps
from ..toolkit import preferences, runner, toolkit_link
from ..toolkit.units import mm_per_unit
from . import device_list, live_cut, live_draw, live_session, stroke_path

TIMER_INTERVAL_S = 1.0 / 120.0

_session: live_session.LiveServo | None = None
_scene_name = ""
_last_error = ""


def current() -> live_session.LiveServo | None:
    return _session


def last_error() -> str:
    return _session.error if _session is not None and _session.error else _last_error


def _scene():
    return bpy.data.scenes.get(_scene_name) if _scene_name else None


def link_steps(timeout_s: float = runner.QUICK_TIMEOUT_S) -> steps.Steps:
    try:
        return (yield from toolkit_link.link_steps(preferences.executable(), timeout_s=timeout_s))
    except runner.ToolkitError as error:
        raise live_session.LiveServoError(str(error)) from None


def link(timeout_s: float = runner.QUICK_TIMEOUT_S):
    """The toolkit's modules (link_steps in one call)."""
    return steps.run_to_end(link_steps(timeout_s))


def log_path(scene) -> str:
    return os.path.join(work_folder.work_directory(scene), "servo.log")


def scene_named(name: str):
    """The scene a job works for, looked up again after every wait (an undo or a file load
    in between replaces Blender's data); LiveServoError once it is gone."""
    scene = bpy.data.scenes.get(name)
    if scene is None:
        raise live_session.LiveServoError(f"the scene {name!r} is gone")
    return scene


def start_steps(scene_name: str) -> steps.Steps[live_session.LiveServo]:
    """Start the servo (stopping an earlier one); LiveServoError for the panel."""
    global _session, _scene_name, _last_error
    scene = scene_named(scene_name)
    live = scene.hapticut_live
    port, realtime = live.port, live.realtime
    if _session is not None:
        yield from stop_steps()
    _last_error = ""
    try:
        modules = yield from link_steps()
        scene = scene_named(scene_name)
        path = log_path(scene)
        # Recordings (Record, Simulate Stroke) go to the scene's work folder only.
        work = work_folder.work_directory(scene)
        _session = yield from live_session.start_steps(
            modules, path, port=port, realtime=realtime, extra=("--record-dir", work)
        )
    except live_session.LiveServoError as error:
        _last_error = str(error)
        raise
    live = scene_named(scene_name).hapticut_live
    live.log_path, live.error = path, ""
    _scene_name = scene_name
    _register()
    return _session


def refresh_devices_steps(scene_name: str, rate_Hz: float | None = None) -> steps.Steps[dict]:
    """*Refresh devices*: run the servo's listing at rate_Hz (the panel's rate), its
    stiffness limits at that rate; the panel shows a failure (LiveServoError). Everything it
    waits for (asking the toolkit for its servo the first time, then the listing) is
    bounded by device_list.LIST_TIMEOUT_S together."""
    live = scene_named(scene_name).hapticut_live
    rate_Hz = live.rate_Hz if rate_Hz is None else rate_Hz
    deadline = time.monotonic() + device_list.LIST_TIMEOUT_S
    try:
        servo = (yield from link_steps(timeout_s=device_list.LIST_TIMEOUT_S)).servo
        listing = yield from device_list.refresh_steps(
            servo, max(0.1, deadline - time.monotonic()), rate_Hz
        )
    except (live_session.LiveServoError, device_list.DeviceListError) as error:
        live = scene_named(scene_name).hapticut_live
        live.device_error = f"devices not listed: {error}"
        raise live_session.LiveServoError(live.device_error) from None
    scene_named(scene_name).hapticut_live.device_error = ""
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


def _limit_problems(scene, listing: dict, bindings: list[str], settings: dict, rate_Hz: float):
    problems = []
    for text in bindings:
        name, _, device = text.partition("=")
        limits = device_list.limits_for(listing, device)
        springs = blade_springs(scene, name)
        found = device_list.settings_problems(settings, limits, rate_Hz, springs)
        problems += [f"{name} ({device}): {problem}" for problem in found]
    if problems:
        raise live_session.LiveServoError("; ".join(problems) + " (lower it in the panel)")


def listing_is_current(rate_Hz: float) -> bool:
    """The kept device listing holds the limits at this rate."""
    return device_list.cached() is not None and device_list.listed_rate() == float(rate_Hz)


def check_limits_steps(
    scene_name: str, bindings: list[str], settings: dict, rate_Hz: float = 1000.0
) -> steps.Steps[None]:
    """Refuse settings above a bound device's limits at the servo's rate (LiveServoError naming
    blade, device and limit); the listing is read first if it was not yet, or again if the
    kept one's stiffness limits are for another rate (the servo's rule, not the add-on's)."""
    if not settings:
        return
    if not listing_is_current(rate_Hz):
        yield from refresh_devices_steps(scene_name, rate_Hz)
    _limit_problems(scene_named(scene_name), device_list.cached(), bindings, settings, rate_Hz)


def check_limits(context, bindings: list[str], settings: dict, rate_Hz: float = 1000.0) -> None:
    """check_limits_steps in one call."""
    steps.run_to_end(check_limits_steps(context.scene.name, bindings, settings, rate_Hz))


def requested_settings(live) -> dict:
    settings = {}
    if live.stiffness_N_per_mm > 0:
        settings["stiffness_N_per_mm"] = live.stiffness_N_per_mm
    if live.max_force_N > 0:
        settings["max_force_N"] = live.max_force_N
    if live.max_torque_N_mm > 0:
        settings["max_torque_N_mm"] = live.max_torque_N_mm
    return settings


def built_scene(scene) -> tuple[str, str]:
    path = building.scene_file(scene)
    if path is None:
        raise live_session.LiveServoError(work_folder.no_build_reason(scene))
    preview = os.path.join(os.path.dirname(path), building.PREVIEW_FILE)
    return path, preview


def ensure_session_steps(scene_name: str) -> steps.Steps[live_session.LiveServo]:
    if _session is None or not _session.alive:
        return (yield from start_steps(scene_name))
    return _session


def refuse_at_once(scene, bindings: list[str], settings: dict, rate_Hz: float) -> None:
    """What Go Live and Simulate Stroke refuse without waiting for anything, in the job's
    order: settings above the device's limits, then no scene built. When the limits need the
    device listing read first, the job checks both. LiveServoError, also on the panel."""
    if settings and not listing_is_current(rate_Hz):
        return
    live = scene.hapticut_live
    try:
        if settings:
            _limit_problems(scene, device_list.cached(), bindings, settings, rate_Hz)
        built_scene(scene)
    except live_session.LiveServoError as error:
        live.error = str(error)
        raise


def start_job(name: str, scene_name: str, work: steps.Steps, show_error: bool = True) -> jobs.Job:
    """Run the work as a job (after those asked for before), its error shown on the scene's
    live panel (unless the work shows it itself)."""
    shown = jobs.shows_error_in(scene_name, "hapticut_live") if show_error else None
    return jobs.start(name, scene_name, work, on_error=shown)


def go_live(context) -> jobs.Job:
    """Start the Go Live job (go_live_steps), after what can be refused at once."""
    scene = context.scene
    live = scene.hapticut_live
    refuse_at_once(scene, devices(scene), requested_settings(live), live.rate_Hz)
    return start_job("Go Live", scene.name, go_live_steps(scene.name))


def go_live_steps(scene_name: str) -> steps.Steps[None]:
    """Start (if needed) and run the scene with the panel's devices and settings."""
    scene = scene_named(scene_name)
    live = scene.hapticut_live
    bindings, settings, rate_Hz = devices(scene), requested_settings(live), live.rate_Hz
    yield from check_limits_steps(scene_name, bindings, settings, rate_Hz)
    path, preview = built_scene(scene_named(scene_name))
    digest = scene_named(scene_name).hapticut.build_hash
    session = yield from ensure_session_steps(scene_name)
    yield from live_session.run_steps(session, path, bindings, rate_Hz, settings=settings)
    session.build_digest = digest
    live = scene_named(scene_name).hapticut_live
    session.preview_path = live.preview_path = preview
    live.error = ""
    if live.force_shading:  # The servo may refuse it (docs/protocol.md): say why, run on.
        try:
            live_session.request(session, "set_parameters", shading=True)
        except live_session.LiveServoError as error:
            live.error = f"force shading not applied: {error}"


def engage(engaged: bool) -> None:
    if _session is None:
        raise live_session.LiveServoError("no servo: Start it first")
    live_session.request(_session, "engage", engaged)


def reset_cuts() -> None:
    if _session is None:
        raise live_session.LiveServoError("no servo: Start it first")
    live_session.request(_session, "reset_cuts")


def record_live(scene) -> str:
    """Toggle recording of the live run; the path while recording, "" once stopped."""
    session = _session
    if session is None or not session.running:
        raise live_session.LiveServoError("nothing runs: Go live first")
    live = scene.hapticut_live
    if session.status.get("recording", {}).get("active"):
        live_session.request(session, "stop_recording")
        session.status = live_session.request(session, "status")
        live.recording_path = session.recording_path
        return ""
    folder = os.path.join(work_folder.work_directory(scene), "recordings")
    path = os.path.join(folder, time.strftime("live-%Y%m%d-%H%M%S.rec"))
    os.makedirs(folder, exist_ok=True)
    recording_stamp.write(path, session.build_digest, scene.name)
    live_session.request(session, "record", path)
    session.recording_path = path
    session.status = live_session.request(session, "status")
    return path


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
            if scene is not None:
                live_cut.update(scene, session)
    except Exception as error:  # Never a traceback out of a timer: the panel says it.
        session.error = f"{type(error).__name__}: {error}"
    live_draw.tag_redraw()
    return TIMER_INTERVAL_S if session.alive else None


def _register() -> None:
    if not bpy.app.timers.is_registered(timer):
        bpy.app.timers.register(timer, first_interval=TIMER_INTERVAL_S)
    live_draw.add_handler(current)


def timer_registered() -> bool:
    return bpy.app.timers.is_registered(timer)


def stop_steps() -> steps.Steps[None]:
    """Stop the servo (its force ramps to zero, waited for in steps); remove the timer and
    the draw handler."""
    global _session
    session, _session = _session, None
    if bpy.app.timers.is_registered(timer):
        bpy.app.timers.unregister(timer)
    live_draw.remove_handler()
    if session is not None:
        yield from live_session.stop_steps(session)


def stop() -> None:
    """stop_steps in one call (unregister, loading another file: nothing may outlive them)."""
    steps.run_to_end(stop_steps())


@persistent
def _on_load_pre(*_args) -> None:
    jobs.cancel_all()
    stop()


def add_handlers() -> None:
    if _on_load_pre not in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.append(_on_load_pre)


def remove_handlers() -> None:
    if _on_load_pre in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(_on_load_pre)
