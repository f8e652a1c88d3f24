"""Work run in a forked child process while the parent goes on with its own.

pymeshlab holds the GIL through a filter, so a thread would not run beside one; a forked
child does, on a second core. Forking is safe only in a process that runs nothing else, so a
process allows it itself (allow(); the build-request command does, the process the add-on
starts for Check Scene and Build Scene), on Linux only (fork is the platform's own way to start
a process there; on macOS a forked child of a process that loaded Qt may crash), only while
no other Python thread runs (a fork copies no thread, and a lock one held would stay held in
the child), and only with a core free for the child. Elsewhere the work runs in the parent
when its result is asked for.

The child is in the parent's process group (a cancel that ends the group ends it), dies with
the parent (Linux's parent-death signal), sends its result pickled through a pipe and ends
with os._exit (no cleanup of the parent's state). The parent kills and reaps it in any case,
and does the work itself when the child sent nothing (it failed, or was killed).
"""

from __future__ import annotations

import contextlib
import os
import pickle
import select
import signal
import sys
import threading
import time
from collections.abc import Callable
from typing import Generic, TypeVar

T = TypeVar("T")

_allowed = False
# A child that has not answered this long after the parent asked (and at least this many
# times as long as it had run before) is taken for hung: a lock held at the fork by a thread
# Python does not know of would hold it forever. The parent then does the work itself.
HUNG_AFTER_S = 10.0
HUNG_AFTER_SHARE = 4.0


def allow(allowed: bool = True) -> None:
    """Let this process fork children for work beside its own (module doc): only a process
    that runs nothing but the caller's work should."""
    global _allowed
    _allowed = allowed


def can_fork() -> bool:
    """Whether Beside forks now: allowed, on Linux, no other thread, and a core free for the
    child (second_core_free)."""
    return (
        _allowed
        and sys.platform.startswith("linux")
        and threading.active_count() == 1
        and second_core_free()
    )


def second_core_free() -> bool:
    """Whether this process has a second core, and the machine's load leaves one free: its
    last minute's average, and the processes runnable now (the average lags a minute behind
    work that has just begun), this process among them. On a busy machine the child would
    only take turns with the parent and the other work, and forking it costs time of its own
    (the pages parent and child write are copied)."""
    cores = len(os.sched_getaffinity(0))
    return cores > 1 and os.getloadavg()[0] < cores and runnable() < cores


def runnable() -> int:
    """How many processes (threads) are runnable now, this one among them (Linux's
    /proc/loadavg; 1 where it cannot be read)."""
    try:
        with open("/proc/loadavg") as file:
            return int(file.read().split()[3].split("/")[0])
    except (OSError, ValueError, IndexError):
        return 1


class Beside(Generic[T]):
    """work() run in a forked child from now on, where forking is allowed (module doc);
    result() is its value. Close it (or use it as a context manager) to end the child."""

    def __init__(self, work: Callable[[], T]) -> None:
        self.work = work
        self.pid: int | None = None
        self.pipe: int | None = None
        self.started = time.monotonic()
        if not can_fork():
            return
        parent = os.getpid()
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # pragma: no cover - the child: coverage does not follow it
            code = 1
            try:
                os.close(read)
                signal.signal(signal.SIGTERM, signal.SIG_DFL)
                signal.signal(signal.SIGINT, signal.SIG_DFL)
                _die_with(parent)
                data = pickle.dumps(work())
                with os.fdopen(write, "wb") as pipe:
                    pipe.write(data)
                code = 0
            finally:
                os._exit(code)
        os.close(write)
        self.pid, self.pipe = pid, read

    @property
    def forked(self) -> bool:
        return self.pid is not None

    def ready(self) -> bool:
        """Whether result() would not wait for the child (it has answered or ended)."""
        if self.pipe is None:
            return False
        return bool(select.select([self.pipe], [], [], 0)[0])

    def result(self) -> T:
        """work()'s value: the child's (waits for it), or work() run here when there is no
        child or it sent nothing whole."""
        if self.pipe is not None:
            data = self._read()
            self.close()
            if data:
                try:
                    return pickle.loads(data)
                except Exception:  # noqa: BLE001 - cut short: do the work here
                    pass
        return self.work()

    def _read(self) -> bytes:
        patience = max(HUNG_AFTER_S, HUNG_AFTER_SHARE * (time.monotonic() - self.started))
        deadline = time.monotonic() + patience
        chunks = []
        while True:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.pipe], [], [], left)[0]:
                return b""
            chunk = os.read(self.pipe, 1 << 16)
            if not chunk:
                return b"".join(chunks)
            chunks.append(chunk)

    def close(self) -> None:
        """End the child (killed if it still runs, and reaped)."""
        if self.pipe is not None:
            os.close(self.pipe)
            self.pipe = None
        if self.pid is not None:
            with contextlib.suppress(ProcessLookupError):  # Ended already.
                os.kill(self.pid, signal.SIGKILL)
            with contextlib.suppress(ChildProcessError):
                os.waitpid(self.pid, 0)
            self.pid = None

    def __enter__(self) -> Beside[T]:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _die_with(parent: int) -> None:  # pragma: no cover - runs in the child
    """The child gets SIGKILL when its parent dies (a parent killed alone, not its group)."""
    import ctypes

    pr_set_pdeathsig = 1
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, int(signal.SIGKILL))
    if os.getppid() != parent:  # The parent died before the signal was asked for.
        os._exit(1)
