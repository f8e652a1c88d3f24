"""Work too long for one call on Blender's main thread, written as a generator of short steps.

A step is what runs between two ``yield``s; each yields a short text of what it waits for
("starting the servo"). Anything that waits on another process (a child of the toolkit, the
servo starting or loading) yields while it waits instead of sleeping, so no step blocks the
UI. ``run_to_end`` runs the steps in one call for code that may wait (a script, the servo's
shutdown at unregister). ``jobs.py`` runs them from a timer, one job at a time.

No bpy here.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import tempfile
import time
from collections.abc import Generator
from dataclasses import dataclass
from typing import TypeVar

T = TypeVar("T")
Steps = Generator[str, None, T]

# run_to_end sleeps this long between steps that wait.
WAIT_S = 0.002


@dataclass(frozen=True)
class ChildResult:
    returncode: int
    stdout: str
    stderr: str


class ChildTimeoutError(RuntimeError):
    """The child ran longer than it was given; it was killed."""


def run_to_end(steps: Steps[T], wait_s: float = WAIT_S) -> T:
    """Run the steps to their end in this call; their result."""
    while True:
        try:
            next(steps)
        except StopIteration as done:
            return done.value
        time.sleep(wait_s)


def started(later: Steps[T]) -> Steps[T]:
    """The steps with their first step run now (a child started, say), the rest to run with
    ``yield from`` later; closing them ends them as closing the original would."""
    try:
        first = next(later)
    except StopIteration as done:
        return _ended(done.value)
    return _resumed(first, later)


def _ended(value: T) -> Steps[T]:
    return value
    yield  # A generator that ends at once with the value.


def _resumed(first: str, rest: Steps[T]) -> Steps[T]:
    try:
        yield first
        return (yield from rest)
    finally:
        rest.close()


def child(
    command: list[str], timeout_s: float, what: str, env: dict[str, str] | None = None
) -> Steps[ChildResult]:
    """Run a command to its end, yielding ``what`` while it runs; its exit code and output.
    ChildTimeoutError (the child killed) after timeout_s; OSError when it cannot start.

    The output goes to temporary files, not pipes: a child writing more than a pipe holds
    would wait for a reader that only reads at its end."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        process = subprocess.Popen(
            command, stdout=out, stderr=err, stdin=subprocess.DEVNULL, env=env
        )
        deadline = time.monotonic() + timeout_s
        try:
            while process.poll() is None:
                if time.monotonic() > deadline:
                    raise ChildTimeoutError(f"timed out after {timeout_s:g} seconds")
                yield what
        finally:
            if process.poll() is None:
                process.kill()
                process.wait()
        out.seek(0)
        err.seek(0)
        decode = {"encoding": "utf-8", "errors": "replace"}
        return ChildResult(
            process.returncode, out.read().decode(**decode), err.read().decode(**decode)
        )


def end_group(process: subprocess.Popen, grace_s: float) -> None:
    """End a child started with ``start_new_session=True`` and its process group: SIGTERM to
    the group, up to grace_s for the child to exit, then SIGKILL to what the group still holds;
    the child is reaped."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(process.pid, signal.SIGTERM)
    with contextlib.suppress(subprocess.TimeoutExpired):
        process.wait(grace_s)
    with contextlib.suppress(ProcessLookupError):  # What the group still holds goes too.
        os.killpg(process.pid, signal.SIGKILL)
    process.wait()
