"""The running build or check: a ``hapticut build-request`` child process (with ``--check``
for Check Scene: the build's checks without the meshing), polled from a timer. A scene runs
one at a time.

No thread touches bpy: ``poll()`` is a plain function that bpy.app.timers calls on the main
thread (tests call it themselves: timers do not run in background mode). The child writes
its progress as JSON lines into a file of the job's directory; the result appears whole in
the work directory's ``build/`` (the toolkit renames it into place at the end). Cancel kills
the child's process group and removes the job's directory, so nothing is left behind.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, field

from ..background import steps
from ..toolkit import runner

POLL_INTERVAL_S = 0.1
# A check running longer than this is slowed by its meshes' size: the progress suggests a
# Decimate modifier (the progress line names the region and its faces).
SLOW_CHECK_S = 10.0
# After SIGTERM the toolkit removes its temporary files; it gets this long before SIGKILL.
TERMINATE_GRACE_S = 5.0
BUILD_FOLDER = "build"


@dataclass
class Job:
    process: subprocess.Popen
    scene_name: str
    job_dir: str  # Request, meshes, logs, the child's cwd and TMPDIR: removed at the end.
    out_dir: str
    digest: str
    kind: str = "build"  # Or "check" (build-request --check).
    started: float = field(default_factory=time.perf_counter)
    read_offset: int = 0
    pending: str = ""
    stage: str = "starting"
    fraction: float = 0.0
    message: str = ""  # What the toolkit is doing ("repairing Cow (4,300,000 faces)").
    meshing: int = 1  # Which meshing, of meshings, when the build meshes again.
    meshings: int = 1
    problems: list = field(default_factory=list)  # (object, problem) found by a check.
    error: str = ""
    error_object: str = ""
    done_event: dict | None = None
    longest_poll_s: float = 0.0
    on_finish: object = None  # callable(job, ok: bool) run on the main thread at the end.

    @property
    def progress_path(self) -> str:
        return os.path.join(self.job_dir, "progress.jsonl")

    @property
    def stderr_path(self) -> str:
        return os.path.join(self.job_dir, "stderr.log")


_jobs: dict[str, Job] = {}  # Scene name -> its running build.
# Figures of the last finished build (for the measurements), by scene name.
last_figures: dict[str, dict] = {}


def running(scene_name: str) -> Job | None:
    return _jobs.get(scene_name)


def new_job_dir(work_dir: str) -> str:
    os.makedirs(work_dir, exist_ok=True)
    return tempfile.mkdtemp(prefix=".job-", dir=work_dir)


def start(
    executable: str,
    scene_name: str,
    job_dir: str,
    request: str,
    work_dir: str,
    digest: str,
    on_finish,
    kind: str = "build",
) -> Job:
    """Start the build child, or with kind "check" the check child (its own process group,
    cwd and TMPDIR in the job dir)."""
    out_dir = os.path.join(work_dir, BUILD_FOLDER)
    action = ["--check"] if kind == "check" else ["--out", out_dir]
    scratch = os.path.join(job_dir, "tmp")
    os.makedirs(scratch, exist_ok=True)
    env = runner.child_environment(TMPDIR=scratch, PYTHONUNBUFFERED="1")
    with (
        open(os.path.join(job_dir, "progress.jsonl"), "wb") as stdout,
        open(os.path.join(job_dir, "stderr.log"), "wb") as stderr,
    ):
        process = subprocess.Popen(
            [executable, "build-request", request, *action, "--progress", "jsonl"],
            stdout=stdout,
            stderr=stderr,
            stdin=subprocess.DEVNULL,
            cwd=job_dir,
            env=env,
            start_new_session=True,
        )
    job = Job(process, scene_name, job_dir, out_dir, digest, kind=kind, on_finish=on_finish)
    _jobs[scene_name] = job
    return job


def _read_events(job: Job) -> list[dict]:
    try:
        with open(job.progress_path, "rb") as file:
            file.seek(job.read_offset)
            chunk = file.read()
    except OSError:
        return []
    job.read_offset += len(chunk)
    job.pending += chunk.decode("utf-8", "replace")
    *lines, job.pending = job.pending.split("\n")
    events = []
    for line in lines:
        try:
            events.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return events


def _apply(job: Job, event: dict) -> None:
    kind = event.get("event")
    if kind == "progress":
        job.stage = str(event.get("stage", job.stage))
        job.fraction = float(event.get("fraction", job.fraction))
        job.message = str(event.get("message", ""))
        job.meshing, job.meshings = int(event.get("meshing", 1)), int(event.get("meshings", 1))
    elif kind == "error":
        name, problem = event.get("object", ""), event.get("problem", "")
        job.error, job.error_object = str(problem), str(name)
    elif kind == "problem":
        job.problems.append((str(event.get("object", "")), str(event.get("problem", ""))))
    elif kind in ("done", "checked"):
        job.done_event = event


def progress_text(job: Job) -> str:
    """The progress bar's text: the step, which meshing when meshing again, the percentage
    and what the toolkit does ("tetrahedralize, meshing again, 2 of 3: 91%: ...")."""
    text = job.stage
    if job.meshing > 1:
        text += f", meshing again, {job.meshing} of {job.meshings}"
    text += f" {100 * job.fraction:.0f}%"
    if job.message and job.message != job.stage:
        text += f": {job.message}"
    if job.kind == "check" and time.perf_counter() - job.started > SLOW_CHECK_S:
        text += " (large meshes check slowly: a Decimate modifier on them makes it faster)"
    return text


def _stderr_tail(job: Job) -> str:
    try:
        with open(job.stderr_path, encoding="utf-8", errors="replace") as file:
            return runner.last_error_line(file.read()[-20000:])
    except OSError:
        return "(no error output)"


def poll(scene_name: str) -> bool:
    """Read the child's new progress; at its end run on_finish. True while it runs."""
    job = _jobs.get(scene_name)
    if job is None:
        return False
    began = time.perf_counter()
    for event in _read_events(job):
        _apply(job, event)
    finished = job.process.poll() is not None
    if finished:
        for event in _read_events(job):
            _apply(job, event)
        ok = job.process.returncode == 0 and job.done_event is not None
        if not ok and not job.error and not job.problems:
            job.error = (
                f"the {job.kind} failed (exit {job.process.returncode}): {_stderr_tail(job)}"
            )
        job.longest_poll_s = max(job.longest_poll_s, time.perf_counter() - began)
        _finish(job, ok)
        return False
    job.longest_poll_s = max(job.longest_poll_s, time.perf_counter() - began)
    return True


def _finish(job: Job, ok: bool) -> None:
    _jobs.pop(job.scene_name, None)
    try:
        if job.on_finish is not None:
            began = time.perf_counter()
            job.on_finish(job, ok)
            job.longest_poll_s = max(job.longest_poll_s, time.perf_counter() - began)
    finally:
        last_figures[job.scene_name] = {
            "seconds_to_preview": time.perf_counter() - job.started,
            "longest_poll_s": job.longest_poll_s,
            "ok": ok,
        }
        shutil.rmtree(job.job_dir, ignore_errors=True)


def cancel(scene_name: str) -> bool:
    """Kill the build's process group and remove its files; False when none runs."""
    job = _jobs.pop(scene_name, None)
    if job is None:
        return False
    steps.end_group(job.process, TERMINATE_GRACE_S)
    shutil.rmtree(job.job_dir, ignore_errors=True)
    # A SIGKILLed toolkit may leave its staging directory beside the output: remove it.
    parent = os.path.dirname(job.out_dir)
    prefix = f".{os.path.basename(job.out_dir)}.tmp-"
    for name in os.listdir(parent) if os.path.isdir(parent) else ():
        if name.startswith(prefix):
            shutil.rmtree(os.path.join(parent, name), ignore_errors=True)
    return True


def cancel_all() -> None:
    for name in list(_jobs):
        cancel(name)
