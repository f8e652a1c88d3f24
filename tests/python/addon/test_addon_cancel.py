"""Cancelling a build half way kills its child processes and leaves nothing behind."""

import os
import time

import blender_scene
import bpy


def group_members(group: int) -> list[int]:
    """Live processes of a process group (from /proc), zombies excluded."""
    members = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as file:
                fields = file.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == group and fields[0] != "Z":
            members.append(int(entry))
    return members


def all_files(folder) -> list[str]:
    return sorted(
        os.path.relpath(os.path.join(root, name), folder)
        for root, dirs, files in os.walk(folder)
        for name in files + dirs
    )


def test_cancel_half_way_kills_the_child_and_writes_nothing(addon, tmp_path):
    from addon.authoring import build_job, building

    work = tmp_path / "work"
    scene = blender_scene.finger_scene(str(work))
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    job = build_job.running(scene.name)
    group = job.process.pid
    deadline = time.monotonic() + 300
    # Half way: fTetWild is running (in a grandchild process of the same group).
    while scene.hapticut.stage != "tetrahedralize":
        assert building.update(scene.name), scene.hapticut.error
        assert time.monotonic() < deadline
        time.sleep(0.05)
    time.sleep(1.0)
    assert len(group_members(group)) >= 2, "fTetWild's process should be running"
    assert bpy.ops.hapticut.cancel_build() == {"FINISHED"}
    assert build_job.running(scene.name) is None
    assert group_members(group) == []
    assert job.process.poll() is not None
    assert not os.path.exists(job.job_dir)
    assert all_files(work) == []  # No build/, no staging directory, no fTetWild file.
    assert scene.hapticut.status == "cancelled"
    assert not scene.hapticut.running
    assert scene.hapticut.build_hash == ""
    # After a cancel the next build starts afresh (and can be cancelled at once).
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    assert building.cancel_build(scene.name)
    assert all_files(work) == []
