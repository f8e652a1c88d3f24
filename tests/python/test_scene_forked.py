"""Work beside the parent's in a forked child (scenebuild/forked.py): its value is the
parent's own, no child outlives a cancel, and where forking is not allowed, failed or cut
short, the parent does the work itself."""

from __future__ import annotations

import contextlib
import io
import json
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
from hapticut import build_request
from hapticut.build_request import InputCheck, input_problems, read_request
from hapticut.commands import build_request as command
from hapticut.scenebuild import Region, forked, repair
from hapticut.scenefile import Material


@pytest.fixture
def may_fork(monkeypatch):
    """Forking allowed in this process (as the build-request command allows it)."""
    if threading.active_count() != 1:
        pytest.skip("another test left a thread running: this process may not fork")
    monkeypatch.setattr(forked, "_allowed", True)
    monkeypatch.setattr(forked, "second_core_free", lambda: True)  # Whatever the load.


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


@pytest.mark.parametrize(
    ("cores", "load", "running", "free"),
    [({0, 1}, 1.5, 1, True), ({0, 1}, 2.5, 1, False), ({0, 1}, 0.5, 2, False),
     ({0}, 0.0, 1, False)],
)  # fmt: skip
def test_a_child_is_forked_only_with_a_core_free_for_it(monkeypatch, cores, load, running, free):
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: cores)
    monkeypatch.setattr(os, "getloadavg", lambda: (load, load, load))
    monkeypatch.setattr(forked, "runnable", lambda: running)
    assert forked.second_core_free() == free


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


def test_a_child_that_does_not_answer_is_taken_for_hung(monkeypatch, may_fork):
    """A child that does not answer in time (a lock held at the fork by a thread Python does
    not know of would hang it) is killed, and the parent does the work."""
    monkeypatch.setattr(forked, "HUNG_AFTER_S", 0.2)
    monkeypatch.setattr(forked, "HUNG_AFTER_SHARE", 0.0)
    parent = os.getpid()
    beside = forked.Beside(lambda: os.getpid() if os.getpid() == parent else time.sleep(60))
    child = beside.pid
    assert beside.forked and beside.result() == parent and gone(child)


def test_a_child_dies_with_its_parent():
    """A parent killed alone (not its process group) takes its child with it."""
    script = (
        "import os, signal, time\n"
        "from hapticut.scenebuild import forked\n"
        "forked.allow()\n"
        "forked.second_core_free = lambda: True\n"
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
    child = (
        "import sys\n"
        "from hapticut.scenebuild import forked\n"
        "forked.second_core_free = lambda: True  # Whatever the load.\n"
        "from hapticut.cli import main\n"
        "sys.exit(main())\n"
    )
    process = subprocess.Popen(
        [sys.executable, "-c", child, "build-request", str(request), "--check"],
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


def spiked_sphere(in_child: bool):
    """A MeshSet of a fine sphere and a coarse one with a vertex pulled out: their distance
    is that vertex's, a sample every measure takes (the same in every measure). The faces
    around the vertex come first (the part of the way back that the child measures) or last
    (the parent's)."""
    meshes = pymeshlab.MeshSet()
    vertices, faces = icosphere(30.0, 3)
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=vertices, face_matrix=faces))
    vertices, faces = icosphere(30.0, 1)
    vertices[0] *= 34.0 / np.linalg.norm(vertices[0])
    around = (faces == 0).any(axis=1)
    order = [faces[around], faces[~around]]
    faces = np.vstack(order if in_child else order[::-1])
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=vertices, face_matrix=faces))
    return meshes


@pytest.mark.parametrize("in_child", [True, False])
def test_both_ways_measured_at_once_find_what_one_after_the_other_do(
    monkeypatch, may_fork, in_child
):
    meshes = spiked_sphere(in_child)
    monkeypatch.setattr(repair, "AT_ONCE_SAMPLES", 0)
    started = []

    def beside(work):
        started.append(forked.Beside(work))
        assert started[-1].forked
        return started[-1]

    monkeypatch.setattr(repair, "Beside", beside)
    at_once = repair.hausdorff(meshes, 0, 1)
    assert started and started[0].pid is None  # Reaped.
    assert meshes.mesh_number() == 2 and meshes.current_mesh_id() == 1  # As they were.
    monkeypatch.setattr(forked, "_allowed", False)
    assert repair.hausdorff(meshes, 0, 1) == at_once == pytest.approx(4.0, abs=0.3)


def test_a_surface_of_one_large_face_is_measured_one_way_after_the_other(monkeypatch, may_fork):
    """Its way back cannot be cut into two parts of faces by area: the parent measures it."""
    meshes = pymeshlab.MeshSet()
    vertices, faces = icosphere(30.0, 2)
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=vertices, face_matrix=faces))
    sheet = np.array([[-40.0, -40, 0], [40, -40, 0], [0, 40, 0], [0, 0, 1], [1, 0, 1]])
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=sheet, face_matrix=[[0, 1, 2], [2, 3, 4]]))
    monkeypatch.setattr(repair, "AT_ONCE_SAMPLES", 0)
    monkeypatch.setattr(repair, "Beside", lambda work: pytest.fail("a child was forked"))
    measured = repair.hausdorff(meshes, 0, 1)
    assert measured == pytest.approx(30.0, abs=1.0) and meshes.mesh_number() == 2


def regions_with_problems():
    vertices, faces = icosphere(10.0, 2)
    crossing = (
        np.vstack([vertices, vertices + [5.0, 0, 0]]),
        np.vstack([faces, faces + len(vertices)]),
    )
    rigid = Material("a", "rigid")
    return [
        Region("Crossing", *crossing, rigid),
        Region("Open", vertices, faces[1:], rigid),
        Region("Good", vertices + [40.0, 0, 0], faces, rigid),
        Region("Good", vertices + [80.0, 0, 0], faces, rigid),
    ]


def test_the_input_check_beside_finds_what_it_finds_alone(monkeypatch, may_fork):
    monkeypatch.setattr(build_request, "BESIDE_FACES", 0)
    regions = regions_with_problems()
    alone = input_problems(regions)
    assert [name for name, _ in alone] == ["Crossing", "Open", "Good"]
    with InputCheck(regions) as check:
        assert check.beside.forked and check.failed()  # The open region's, known at once.
        assert check.problems() == alone
    with InputCheck(regions[:1]) as check:
        assert check.beside.forked
        assert wait_until(check.failed)  # Its crossing faces, once the child has counted.
        assert check.problems() == alone[:1]


def test_without_a_child_the_input_check_finds_crossing_faces_before_the_layout(
    monkeypatch,
):
    monkeypatch.setattr(build_request, "BESIDE_FACES", 0)
    monkeypatch.setattr(forked, "_allowed", False)
    with InputCheck(regions_with_problems()[:1]) as check:
        assert check.beside is None and check.failed()


def test_check_scene_stops_the_layout_check_for_the_regions_own_problems(tmp_path):
    """Check Scene checks the layout while the input check still runs; a problem it then
    finds ends the layout's check, and is the one reported."""
    vertices, faces = icosphere(10.0, 2)
    np.savez(tmp_path / "ball.npz", vertices=vertices, faces=faces)
    region = {"name": "Ball", "mesh": "ball.npz", "material": {"name": "a", "model": "rigid"}}
    path = tmp_path / "request.json"
    path.write_text(json.dumps({"format": "hapticut.build-request", "version": 1,
                                "regions": [region]}))  # fmt: skip
    request = read_request(path)

    class FoundLater:
        """An input check whose crossing faces are found after the layout's first steps."""

        asked = 0

        def failed(self) -> bool:
            self.asked += 1
            return self.asked > 3

        def problems(self):
            return [("Ball", "the mesh intersects itself (4 faces)")]

    out = io.StringIO()
    assert command._check(request, FoundLater(), command.JsonLines(out)) == 1
    events = [json.loads(line) for line in out.getvalue().splitlines()]
    stages = {e["stage"] for e in events if e["event"] == "progress"}
    assert "repair" in stages and "done" not in stages
    assert [e for e in events if e["event"] != "progress"] == [
        {"event": "problem", "object": "Ball", "problem": "the mesh intersects itself (4 faces)"},
        {"event": "checked", "problems": 1},
    ]
