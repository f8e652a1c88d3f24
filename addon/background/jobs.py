"""The live panel's work in the background: Go Live, Simulate Stroke, Bake, Start, Stop and
Refresh devices run as steps (``steps.py``), one job at a time in the order they were asked
for, one step per timer call, so no operator holds Blender's main thread.

An operator starts its job and returns; started from the UI it stays modal to report how the
job ended and to let Esc cancel it (``FollowsJob``). A script waits with
``bpy.ops.hapticut.wait()``: in background mode no timer runs, and the wait advances the job
itself (``waiting.py``). A job's error goes to the panel (its ``on_error``) and to
``last()``; nothing raises out of the timer.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import bpy

from .steps import Steps

# The timer's interval while a job runs: a step that waits on a child looks again this soon.
INTERVAL_S = 0.005


@dataclass
class Job:
    name: str  # What the panel and the reports call it: "Go Live", "Bake".
    scene_name: str
    steps: Steps
    on_error: Callable[[str], None] | None = None
    stage: str = "starting"  # What the last step said it waits for or does.
    state: str = "running"  # running, done, failed, cancelled
    error: str = ""
    result: object = None
    started: float = field(default_factory=time.perf_counter)
    seconds: float = 0.0
    step_count: int = 0
    longest_step_s: float = 0.0
    longest_step_after: str = ""  # What the job had said before its longest step.

    @property
    def running(self) -> bool:
        return self.state == "running"


_queue: list[Job] = []  # The running job first, then the ones waiting for it.
_last: Job | None = None
# Each job name's longest step over the session and what the job had said before it (for
# the measurements).
longest_steps: dict[str, tuple[float, str]] = {}


def current() -> Job | None:
    """The running job."""
    return _queue[0] if _queue else None


def last() -> Job | None:
    """The job that runs, or else the one that ended last."""
    return current() or _last


def shows_error_in(scene_name: str, settings: str):
    """An on_error that puts the message into the scene's ``error`` of its settings group
    (``hapticut`` for the build panel, ``hapticut_live`` for the live one)."""

    def show(message: str) -> None:
        scene = bpy.data.scenes.get(scene_name)
        if scene is not None:
            getattr(scene, settings).error = message

    return show


def start(
    name: str, scene_name: str, steps: Steps, on_error: Callable[[str], None] | None = None
) -> Job:
    """Run the steps as a job, after the jobs asked for before it."""
    job = Job(
        name,
        scene_name,
        steps,
        on_error,
        stage="waiting for " + _queue[-1].name if _queue else "starting",
    )
    _queue.append(job)
    if not bpy.app.timers.is_registered(timer):
        bpy.app.timers.register(timer, first_interval=0.0)
    return job


def _end(job: Job, state: str, error: str = "") -> None:
    global _last
    job.state, job.error = state, error
    job.seconds = time.perf_counter() - job.started
    _queue.remove(job)
    job.steps = None  # What the steps held (Blender data, a session) goes with them.
    _last = job
    if error and job.on_error is not None:
        job.on_error(error)


def advance() -> bool:
    """Run the running job's next step; False when no job is left (then the timer is
    removed: nothing of the add-on stays registered with Blender without work)."""
    running = _advance()
    if not running:
        stop_timer()
    return running


def _advance() -> bool:
    job = current()
    if job is None:
        return False
    if job.step_count == 0:
        job.started = time.perf_counter()
    began = time.perf_counter()
    before = job.stage
    try:
        job.stage = next(job.steps)
    except StopIteration as done:
        job.result = done.value
        _end(job, "done")
    except Exception as error:  # Never a traceback out of a timer: the panel says it.
        text = str(error) or type(error).__name__
        if not isinstance(error, RuntimeError | OSError):
            text = f"{type(error).__name__}: {error}"
        _end(job, "failed", text)
    spent = time.perf_counter() - began
    job.step_count += 1
    if spent > job.longest_step_s:
        job.longest_step_s, job.longest_step_after = spent, before
    if spent > longest_steps.get(job.name, (0.0, ""))[0]:
        longest_steps[job.name] = (spent, before)
    return bool(_queue)


def cancel(job: Job | None = None) -> None:
    """Stop a job (the running one by default) where it is; its steps' cleanup runs."""
    job = job or current()
    if job is not None and job in _queue:
        job.steps.close()
        _end(job, "cancelled")


def cancel_all() -> None:
    """Cancel every job, the waiting ones first."""
    for job in reversed(list(_queue)):
        cancel(job)


def timer():
    """bpy.app.timers callback: one step; the next interval, None once no job runs."""
    return INTERVAL_S if _advance() else None


def stop_timer() -> None:
    if bpy.app.timers.is_registered(timer):
        bpy.app.timers.unregister(timer)


class FollowsJob:
    """Mixin for an operator whose execute() starts a job: from the UI it stays modal until
    the job ends, reports how it ended, and Esc cancels it."""

    def invoke(self, context, event):
        result = self.execute(context)
        job = _queue[-1] if _queue else None
        if "FINISHED" in result and job is not None:
            self._job = job
            manager = context.window_manager
            # Events wake modal(): this one comes even while the user does nothing.
            self._wake = manager.event_timer_add(0.1, window=context.window)
            manager.modal_handler_add(self)
            return {"RUNNING_MODAL"}
        return result

    def modal(self, context, event):
        job = self._job
        if not job.running:
            context.window_manager.event_timer_remove(self._wake)
        if job.running:
            if event.type == "ESC" and event.value == "PRESS":
                cancel(job)
                context.window_manager.event_timer_remove(self._wake)
                self.report({"WARNING"}, f"{job.name} cancelled")
                return {"CANCELLED"}
            return {"PASS_THROUGH"}
        if job.state == "failed":
            self.report({"ERROR"}, f"{job.name}: {job.error}")
            return {"CANCELLED"}
        if job.state == "cancelled":
            return {"CANCELLED"}
        for level, text in self.summary(job.result):
            self.report({level}, text)
        return {"FINISHED"}

    def summary(self, result) -> list[tuple[str, str]]:
        """What to report when the job is done: (level, text) pairs."""
        return [("INFO", f"{self._job.name}: done in {self._job.seconds:.1f} s")]
