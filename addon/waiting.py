"""Waiting, from a script, for the scene's background work: its build or check, and the
add-on's job (Go Live, Simulate Stroke with its bake, Bake, Start, Stop, Refresh devices). In
the GUI bpy.app.timers run them; in background mode (``blender -b``, the bpy module) no timer
runs, so the wait calls what the timers would: ``building.update`` for the build,
``jobs.advance`` for the job and ``live_link.timer`` for the live link it follows; and, for a
live session a script drives (``run_live``), the live link alone for a while (docs/addon.md,
"Scripting").
"""

from __future__ import annotations

import time

import bpy

from .authoring import build_job, building
from .background import jobs
from .live import live_link

# A job's steps wait on children and the servo: look again this soon.
JOB_POLL_INTERVAL_S = 0.002


class WaitTimeoutError(RuntimeError):
    """The work goes on after the wait gave up; the message says which."""


def wait(scene, timeout_s: float) -> float:
    """Follow the build and the job until both are over; the seconds waited.
    WaitTimeoutError after timeout_s (nothing is cancelled)."""
    began = time.monotonic()
    while True:
        building_now = building.update(scene.name)
        job_now = jobs.advance()
        if job_now and live_link.timer_registered():
            live_link.timer()
        if not building_now and not job_now:
            return time.monotonic() - began
        if time.monotonic() - began > timeout_s:
            what = "the build" if building_now else jobs.current().name
            raise WaitTimeoutError(f"{what} is still running after {timeout_s:g} s")
        time.sleep(JOB_POLL_INTERVAL_S if job_now else build_job.POLL_INTERVAL_S)


def run_live(seconds: float) -> int:
    """Run the live link for seconds as its timer does in the GUI (the viewport blades' poses
    sent, the stream read); the number of timer calls. NoLiveSessionError when none runs
    or it is lost meanwhile."""
    if not live_link.timer_registered():
        raise NoLiveSessionError("no live session: Start and Go Live first")
    # The script moved the blades: their matrix_world follows only an update (the GUI's
    # depsgraph does it by itself).
    bpy.context.view_layer.update()
    began, calls = time.monotonic(), 0
    while True:
        interval = live_link.timer()
        calls += 1
        if interval is None:
            raise NoLiveSessionError(f"the live session ended: {live_link.last_error()}")
        if time.monotonic() - began >= seconds:
            return calls
        time.sleep(interval)


class NoLiveSessionError(RuntimeError):
    """run_live has no session to run; the message says why."""
