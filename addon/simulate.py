"""Simulate Stroke: every blade's keyframed animation sampled into a sim path, run through
the servo as fast as possible and recorded (the live link, ``live_link``), then baked
(``baking``). It sits above both, so the live link never calls the bake."""

from __future__ import annotations

import os
import time

from .authoring import recording_stamp, work_folder
from .authoring.exchange import scene_objects
from .background import jobs, steps, undo_steps
from .bake import baking
from .live import live_link, live_session, stroke_path

# Figures of the last Simulate stroke (for the measurements).
last_simulate: dict = {}


def simulate(context) -> jobs.Job:
    """Start the Simulate Stroke job (simulate_steps), after what can be refused at once."""
    scene = context.scene
    props = scene.hapticut_live
    bindings = [f"{obj.name}=sim:" for obj in scene_objects(scene, "BLADE")]
    live_link.refuse_at_once(scene, bindings, live_link.requested_settings(props), props.rate_Hz)
    return live_link.start_job("Simulate Stroke", scene.name, simulate_steps(scene.name))


def simulate_steps(scene_name: str) -> steps.Steps[dict]:
    """Sample every blade's animation into a sim path, run it as fast as possible, recording,
    follow it to its end (the live timer reads its frames), then bake it if the panel says
    so; the figures (``last_simulate``)."""
    global last_simulate
    began = time.perf_counter()
    scene = live_link.scene_named(scene_name)
    props = scene.hapticut_live
    path, preview = live_link.built_scene(scene)
    folder = os.path.join(work_folder.work_directory(scene), "stroke")
    rate_Hz, settings = props.rate_Hz, live_link.requested_settings(props)
    hand, bake_after = (1 if props.simulated_hand else 0), props.bake_after_simulate
    bindings = []
    for name in [obj.name for obj in scene_objects(scene, "BLADE")]:
        poses = yield from stroke_path.sample_poses_steps(scene_name, name, rate_Hz)
        file = stroke_path.write_path(poses, os.path.join(folder, f"{name}.path.json"))
        if "," in file or "=" in name:
            raise live_session.LiveServoError(f"{name}: the path {file} cannot hold ',' ")
        bindings.append(f"{name}=sim:{file},hand={hand},hold_s=0")
    sampled = time.perf_counter()
    yield from live_link.check_limits_steps(scene_name, bindings, settings, rate_Hz)
    session = yield from live_link.ensure_session_steps(scene_name)
    record = os.path.join(folder, "stroke.rec")
    recording_stamp.write(record, scene.hapticut.build_hash, scene_name)
    yield from live_session.run_steps(
        session,
        path,
        bindings,
        rate_Hz,
        as_fast_as_possible=True,
        record_path=record,
        settings=settings,
        engage=True,
    )
    session.preview_path = live_link.scene_named(scene_name).hapticut_live.preview_path = preview
    session.simulate = {"began": began, "record": record}
    try:
        # The live timer follows the stroke (its frames, its status) until the servo stops.
        while session.status.get("state") != "stopped":
            if not session.alive:
                raise live_session.LiveServoError(session.error or "the servo stopped")
            yield "simulating the stroke"
    finally:
        session.simulate = None
    if session.state == "simulating":
        session.state = "connected"
    figures = {"servo_s": time.perf_counter() - sampled, "sampled_s": sampled - began}
    live_link.scene_named(scene_name).hapticut_live.recording_path = record
    if bake_after:
        baked = yield from baking.bake_steps(scene_name, session.link, record, preview)
        figures["bake_s"] = baked["seconds"]
        undo_steps.push("Bake stroke")
    figures["total_s"] = time.perf_counter() - began
    figures["ticks"] = session.status.get("ticks", 0)
    last_simulate = figures
    return figures
