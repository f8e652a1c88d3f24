"""Work beside the parent's in a forked child (scenebuild/forked.py): its value is the
parent's own, no child outlives a cancel, and where forking is not allowed, failed or cut
short, the parent does the work itself."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pymeshlab
import pytest
from build_test_support import icosphere
from hapticut.scenebuild import forked, repair


@pytest.fixture
def may_fork(monkeypatch):
    """Forking allowed in this process (as the build-request command allows it)."""
    if threading.active_count() != 1:
        pytest.skip("another test left a thread running: this process may not fork")
    monkeypatch.setattr(forked, "_allowed", True)


def gone(pid: int) -> bool:
    """Whether the process has ended (a zombie no one has reaped yet counts as ended)."""
    try:
        with open(f"/proc/{pid}/stat") as file:
            return file.read().rsplit(")", 1)[1].split()[0] in ("Z", "X")
    except FileNotFoundError:
        return True


def wait_until(condition, seconds: float = 20.0) -> bool:
    deadline = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def test_the_work_runs_in_a_child_and_its_value_comes_back(may_fork):
    beside = forked.Beside(os.getpid)
    child = beside.pid
    assert beside.forked and child != os.getpid()
    assert beside.result() == child
    assert gone(child)  # Reaped.


def test_without_leave_to_fork_the_parent_does_the_work(monkeypatch):
    monkeypatch.setattr(forked, "_allowed", False)
    beside = forked.Beside(os.getpid)
    assert not beside.forked and not beside.ready()
    assert beside.result() == os.getpid()


def test_a_running_thread_keeps_the_work_in_the_parent(may_fork):
    stop = threading.Event()
    thread = threading.Thread(target=stop.wait)
    thread.start()
    try:
        beside = forked.Beside(os.getpid)
        assert not beside.forked and beside.result() == os.getpid()
    finally:
        stop.set()
        thread.join()


def test_a_child_that_fails_or_is_killed_leaves_the_work_to_the_parent(may_fork):
    parent = os.getpid()

    def fails_in_a_child() -> int:
        if os.getpid() != parent:
            raise RuntimeError("only in the child")
        return parent

    assert forked.Beside(fails_in_a_child).result() == parent
    beside = forked.Beside(lambda: os.getpid() if os.getpid() == parent else time.sleep(60))
    child = beside.pid
    os.kill(child, signal.SIGKILL)
    assert beside.result() == parent and gone(child)


def test_a_child_dies_with_its_parent():
    """A parent killed alone (not its process group) takes its child with it."""
    script = (
        "import os, signal, time\n"
        "from hapticut.scenebuild import forked\n"
        "forked.allow()\n"
        "beside = forked.Beside(lambda: time.sleep(60))\n"
        "print(beside.pid, flush=True)\n"
        "os.kill(os.getpid(), signal.SIGKILL)\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60
    )
    child = int(result.stdout)
    assert wait_until(lambda: gone(child))


def test_a_cancel_of_check_scene_leaves_no_child_behind(tmp_path):
    """The add-on cancels by ending the child's process group (addon/background/steps.py):
    the forked children beside it end too."""
    from measure_check_time import sample_mesh, write_request

    request = write_request(tmp_path, sample_mesh(), 100.0)
    process = subprocess.Popen(
        [sys.executable, "-m", "hapticut.cli", "build-request", str(request), "--check"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
    )  # fmt: skip
    children: set[int] = set()
    try:
        while process.poll() is None and not children:
            try:
                with open(f"/proc/{process.pid}/task/{process.pid}/children") as file:
                    children = {int(pid) for pid in file.read().split()}
            except FileNotFoundError:
                break
            time.sleep(0.002)
    finally:
        with contextlib.suppress(ProcessLookupError):  # As the add-on's cancel does.
            os.killpg(process.pid, signal.SIGTERM)
        process.wait(60)
    assert children, "the check forked no child"
    assert wait_until(lambda: all(gone(pid) for pid in children))


def spiked_sphere():
    """A MeshSet of a fine sphere and a coarse one with a vertex pulled out: their distance
    is that vertex's, a sample every measure takes (the same in every measure)."""
    meshes = pymeshlab.MeshSet()
    vertices, faces = icosphere(30.0, 3)
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=vertices, face_matrix=faces))
    vertices, faces = icosphere(30.0, 1)
    vertices[0] *= 34.0 / np.linalg.norm(vertices[0])
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=vertices, face_matrix=faces))
    return meshes


def test_both_ways_measured_at_once_find_what_one_after_the_other_do(monkeypatch, may_fork):
    meshes = spiked_sphere()
    monkeypatch.setattr(repair, "AT_ONCE_SAMPLES", 0)
    started = []

    def beside(work):
        started.append(forked.Beside(work))
        return started[-1]

    monkeypatch.setattr(repair, "Beside", beside)
    at_once = repair.hausdorff(meshes, 0, 1)
    assert started and started[0].pid is None  # Forked, and reaped.
    monkeypatch.setattr(forked, "_allowed", False)
    assert repair.hausdorff(meshes, 0, 1) == at_once == pytest.approx(4.0, abs=0.3)
