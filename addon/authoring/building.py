"""Tetrahedralize from start to preview: write the request, start the child, follow it
(``update`` is what the timer calls), show the preview and the report at the end. Check
Scene's toolkit check runs the same way (a child of kind "check"), its problems recorded at
the end."""

from __future__ import annotations

import functools
import json
import os
import shutil

import bpy

from ..background import undo_steps
from ..toolkit import preferences, runner
from . import build_job, checking, exchange, work_folder, work_owner
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
    _refuse_while_running(scene.name)
    settings.error = ""
    messages = checking.check_scene(context)
    if messages:
        raise BuildRefusedError(messages[0])
    try:
        table = preferences.material_table(context)
        executable = preferences.executable(context)
    except runner.ToolkitError as error:
        settings.error = str(error)
        raise BuildRefusedError(str(error)) from None
    try:
        work_dir, job_dir, request, digest = _write_request(context, table)
    except exchange.SceneProblemError as problem:
        checking.record(scene, [problem])
        raise BuildRefusedError(str(problem)) from None
    out_dir = os.path.join(work_dir, build_job.BUILD_FOLDER)
    if digest == work_folder.digest_on_disk(out_dir) and _show_again(scene, out_dir, digest):
        shutil.rmtree(job_dir, ignore_errors=True)
        settings.status = "unchanged: not rebuilt"
        undo_steps.push("Tetrahedralize preview")
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
    _follow(scene, "building")
    return "started"


def start_check(context) -> list[str]:
    """Check Scene: Blender's checks now, their problems returned; when they pass, the
    build's own checks without the meshing in a child (followed like a build; the problems are
    recorded when it ends) and []. Raises BuildRefusedError while a job runs."""
    scene = context.scene
    _refuse_while_running(scene.name)
    messages = checking.check_scene(context)
    if messages:
        return messages
    try:
        table = preferences.material_table(context)
        executable = preferences.executable(context)
    except runner.ToolkitError as error:
        return checking.record(scene, [exchange.SceneProblemError("", str(error))])
    try:
        work_dir, job_dir, request, digest = _write_request(context, table)
    except exchange.SceneProblemError as problem:
        return checking.record(scene, [problem])
    build_job.start(
        executable,
        scene.name,
        job_dir,
        request,
        work_dir,
        digest,
        functools.partial(_checked, scene.name),
        kind="check",
    )
    _follow(scene, "checking")
    return []


def _write_request(context, table) -> tuple[str, str, str, str]:
    """The builder's request for the context's scene in a new job directory of its work
    folder: (work folder, job directory, request, digest). On a SceneProblemError the job
    directory is removed."""
    work_dir = work_folder.work_directory(context.scene)
    job_dir = build_job.new_job_dir(work_dir)
    try:
        request, digest = exchange.write_request(
            context.scene, context.evaluated_depsgraph_get(), table, job_dir
        )
    except exchange.SceneProblemError:
        shutil.rmtree(job_dir, ignore_errors=True)
        raise
    return work_dir, job_dir, request, digest


def _refuse_while_running(scene_name: str) -> None:
    job = build_job.running(scene_name)
    if job is not None:
        raise BuildRefusedError(f"a {job.kind} of this scene is running: cancel it first")


def _follow(scene, status: str) -> None:
    """The job just started: show its progress and poll it from a timer."""
    settings = scene.hapticut
    settings.running, settings.progress, settings.stage = True, 0.0, "starting"
    settings.status = status
    if not bpy.app.background:
        bpy.app.timers.register(functools.partial(timer_tick, scene.name), first_interval=0.1)


def update(scene_name: str) -> bool:
    """Follow the scene's build: progress into its properties; True while it runs."""
    still_running = build_job.poll(scene_name)
    job = build_job.running(scene_name)
    scene = _scene(scene_name)
    if job is not None and scene is not None:
        # running too: an undo may have restored a step from before the build started.
        scene.hapticut.running = True
        scene.hapticut.progress, scene.hapticut.stage = job.fraction, job.stage
    _redraw()
    return still_running


def timer_tick(scene_name: str):
    """bpy.app.timers callback: the next interval, or None when the build is over."""
    return build_job.POLL_INTERVAL_S if update(scene_name) else None


def cancel_build(scene_name: str) -> bool:
    """Cancel the scene's build or check; False when none runs."""
    job = build_job.running(scene_name)
    cancelled = build_job.cancel(scene_name)
    scene = _scene(scene_name)
    if cancelled and scene is not None:
        scene.hapticut.running = False
        if job.kind == "build":
            kept = work_folder.built_folder(scene) is not None
            scene.hapticut.status = "cancelled: the last build stays" if kept else "cancelled"
        else:
            scene.hapticut.status = f"{job.kind} cancelled"
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
        messages = checking.record(scene, [exchange.SceneProblemError(job.error_object, job.error)])
        _failed(scene, messages[0])
        return
    try:
        _show_build(scene, _into_current_folder(scene, job.out_dir), job.digest)
    except (OSError, ValueError, KeyError) as error:
        _failed(scene, f"cannot read the preview: {error}")
        return
    settings.status = f"built in {job.done_event.get('seconds', 0):.1f} s"
    checking.record(scene, [])
    undo_steps.push("Tetrahedralize preview")


def _into_current_folder(scene, out_dir: str) -> str:
    """Where the finished build is the scene's: out_dir, or, when the scene's folder was
    forked while it built (a Save As), a share of it in the scene's folder now."""
    folder = work_folder.build_folder(scene)
    if folder is None or work_owner.same_file(folder, out_dir):
        return out_dir
    work_owner.share_tree(out_dir, folder)
    return folder


def _failed(scene, error: str) -> None:
    """The build failed: its error, and no report or build of an older scene shown as this
    one's (the older build stays on disk; an unchanged scene shows it again)."""
    settings = scene.hapticut
    settings.status, settings.error = "failed", error
    settings.report_json, settings.build_hash = "", ""


def _show_again(scene, out_dir: str, digest: str) -> bool:
    """The build on disk (the scene's own: its digest) shown again, its preview and report
    read from disk; False when it cannot be (then it is built). Always from disk, even when
    the scene's digest is already this one: an undo may have brought back another build's
    report and preview, or the preview may have been deleted."""
    try:
        _show_build(scene, out_dir, digest)
    except (OSError, ValueError, KeyError):
        return False
    return True


def _show_build(scene, out_dir: str, digest: str) -> None:
    """The build in out_dir becomes the scene's: its preview, report and digest."""
    report = show_preview(scene, os.path.join(out_dir, PREVIEW_FILE))
    work_folder.write_digest(out_dir, digest)
    scene.hapticut.report_json = json.dumps(report)
    scene.hapticut.build_hash = digest


def _checked(scene_name: str, job: build_job.Job, ok: bool) -> None:
    scene = _scene(scene_name)
    if scene is None:
        return
    settings = scene.hapticut
    settings.running, settings.progress, settings.stage = False, 0.0, ""
    problems = [exchange.SceneProblemError(name, text) for name, text in job.problems]
    if job.error:
        problems.append(exchange.SceneProblemError(job.error_object, job.error))
    checking.record(scene, problems)
    if ok:
        settings.status = "checked: ready to build"
    elif job.problems:
        settings.status = f"checked: {len(problems)} problem(s)"
    else:
        settings.status = "check failed"


def scene_file(scene) -> str | None:
    """The scene file of the scene's last build, if it is on disk (work_folder.built_folder)."""
    folder = work_folder.built_folder(scene)
    return os.path.join(folder, exchange.SCENE_FILE) if folder else None
