"""Waiting, from a script, for the scene's background work: its build and a Simulate Stroke
(with the bake at its end). In the GUI bpy.app.timers follow both; in background mode
(``blender -b``, the bpy module) no timer runs, so the wait calls what the timers would:
``building.update`` for the build, ``live.timer`` for the stroke (docs/addon.md, "Scripting").
"""

from __future__ import annotations

import time

from . import build_job, building, live

# The stroke streams frames at 120 Hz: follow it more closely than the build's progress.
STROKE_POLL_INTERVAL_S = 0.005


class WaitTimeoutError(RuntimeError):
    """The work goes on after the wait gave up; the message says which."""


def simulating() -> bool:
    session = live.current()
    return session is not None and session.simulate is not None


def wait(scene, timeout_s: float) -> float:
    """Follow the build and the stroke until both are over; the seconds waited.
    WaitTimeoutError after timeout_s (nothing is cancelled)."""
    began = time.monotonic()
    while True:
        building_now = building.update(scene.name)
        stroke_now = simulating()
        if stroke_now:
            live.timer()
            stroke_now = simulating()
        if not building_now and not stroke_now:
            return time.monotonic() - began
        if time.monotonic() - began > timeout_s:
            what = "the build" if building_now else "the stroke"
            raise WaitTimeoutError(f"{what} is still running after {timeout_s:g} s")
        time.sleep(STROKE_POLL_INTERVAL_S if stroke_now else build_job.POLL_INTERVAL_S)
