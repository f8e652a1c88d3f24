"""Tetrahedralize from start to preview: write the request, start the child, follow it
(``update`` is what the timer calls), show the preview and the report at the end."""

from __future__ import annotations

import functools
import json
import os
import shutil

import bpy

from . import build_job, checking, exchange, preferences, toolkit
from .preview import show_preview

PREVIEW_FILE = "preview.npz"


class BuildRefusedError(Exception):
    """The build cannot start; the message (naming the object) is for self.report."""


def _scene(scene_name: str):
    return bpy.data.scenes.get(scene_name)


def _redraw() -> None:
    manager = bpy.context.window_manager
    for window in manager.windows if manager is not None else ():
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()


def start_build(context) -> str:
    """Start a build of the context's scene; "started" or "unchanged". Raises BuildRefusedError."""
    scene = context.scene
    settings = scene.hapticut
    if build_job.running(scene.name):
        raise BuildRefusedError("a build of this scene is running: cancel it first")
    settings.error = ""
    messages = checking.check_scene(context, with_toolkit=False)
    if messages:
        raise BuildRefusedError(messages[0])
    try:
        table = preferences.material_table(context)
        executable = preferences.executable(context)
    except toolkit.ToolkitError as error:
        settings.error = str(error)
        raise BuildRefusedError(str(error)) from None
    work_dir = build_job.work_directory(scene, bpy.data.filepath)
    job_dir = build_job.new_job_dir(work_dir)
    try:
        request, digest = exchange.write_request(
            scene, context.evaluated_depsgraph_get(), table, job_dir
        )
    except exchange.SceneProblemError as problem:
        shutil.rmtree(job_dir, ignore_errors=True)
        checking.record(scene, [problem])
        raise BuildRefusedError(str(problem)) from None
    preview = os.path.join(work_dir, build_job.BUILD_FOLDER, PREVIEW_FILE)
    if digest == settings.build_hash and os.path.isfile(preview):
        shutil.rmtree(job_dir, ignore_errors=True)
        settings.status = "unchanged: not rebuilt"
        return "unchanged"
    build_job.start(
        executable,
        scene.name,
        job_dir,
        request,
        work_dir,
        digest,
        functools.partial(_finished, scene.name),
    )
    settings.running, settings.progress, settings.stage = True, 0.0, "starting"
    settings.status = "building"
    if not bpy.app.background:
        bpy.app.timers.register(functools.partial(timer_tick, scene.name), first_interval=0.1)
    return "started"


def update(scene_name: str) -> bool:
    """Follow the scene's build: progress into its properties; True while it runs."""
    still_running = build_job.poll(scene_name)
    job = build_job.running(scene_name)
    scene = _scene(scene_name)
    if job is not None and scene is not None:
        scene.hapticut.progress, scene.hapticut.stage = job.fraction, job.stage
    _redraw()
    return still_running


def timer_tick(scene_name: str):
    """bpy.app.timers callback: the next interval, or None when the build is over."""
    return build_job.POLL_INTERVAL_S if update(scene_name) else None


def cancel_build(scene_name: str) -> bool:
    cancelled = build_job.cancel(scene_name)
    scene = _scene(scene_name)
    if cancelled and scene is not None:
        scene.hapticut.running = False
        scene.hapticut.status = "cancelled"
        scene.hapticut.progress, scene.hapticut.stage = 0.0, ""
    return cancelled


def _finished(scene_name: str, job: build_job.Job, ok: bool) -> None:
    scene = _scene(scene_name)
    if scene is None:
        return
    settings = scene.hapticut
    settings.running = False
    settings.progress, settings.stage = (1.0, "done") if ok else (0.0, "")
    if not ok:
        settings.status = "failed"
        settings.error = f"{job.error_object}: {job.error}" if job.error_object else job.error
        checking.record(scene, [exchange.SceneProblemError(job.error_object, job.error)])
        return
    try:
        report = show_preview(scene, os.path.join(job.out_dir, PREVIEW_FILE))
    except (OSError, ValueError, KeyError) as error:
        settings.status, settings.error = "failed", f"cannot read the preview: {error}"
        return
    settings.report_json = json.dumps(report)
    settings.build_hash = job.digest
    settings.status = f"built in {job.done_event.get('seconds', 0):.1f} s"
    checking.record(scene, [])


def scene_file(scene) -> str | None:
    """The last build's scene file, if there is one."""
    path = os.path.join(
        build_job.work_directory(scene, bpy.data.filepath),
        build_job.BUILD_FOLDER,
        exchange.SCENE_FILE,
    )
    return path if os.path.isfile(path) else None
