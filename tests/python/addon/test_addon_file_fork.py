"""A file's build and recordings are its own (docs/addon.md, "A folder is one file's"): Save
As forks the work folder, so a copy rebuilt and stroked leaves the original's build and bake
as they were, and the original refuses the copy's recording, naming both; Save Copy forks the
copy only; a file copied outside Blender says whose folder it found and forks before writing.
"""

import json
import os
import shutil
import time

import bpy
import pytest
from file_scenes import build, cube_scene, exports, simulate_and_bake


def ideal_path(frames) -> list[float]:
    """Where the baked knife is at each frame (x, y, z after one another; Blender units)."""
    scene = bpy.context.scene
    knife = bpy.data.objects["Ideal Knife"]
    path = []
    for frame in frames:
        scene.frame_set(frame)
        path.extend(knife.matrix_world.translation)
    return path


def owner(scene) -> str:
    from addon.authoring import work_folder, work_owner

    return work_owner.owner_of(work_folder.existing_work_directory(scene))


def test_save_as_forks_and_each_file_keeps_its_build_and_stroke(addon, data_home, tmp_path):
    from addon.authoring import work_folder

    scene = cube_scene()
    build(scene)
    simulate_and_bake(scene)
    frames = range(scene.frame_start, scene.frame_end + 1)
    baked_first = ideal_path(frames)
    first = str(tmp_path / "first.blend")
    bpy.ops.wm.save_as_mainfile(filepath=first)
    first_id, first_recording = scene.hapticut.work_id, scene.hapticut_live.recording_path
    assert owner(scene) == first

    # Save Copy: the copy gets a folder of its own; the open file keeps its id.
    copy = str(tmp_path / "copy.blend")
    bpy.ops.wm.save_as_mainfile(filepath=copy, copy=True)
    assert bpy.context.scene.hapticut.work_id == first_id

    # Save As: the open file (now second) forks, with the build and the stroke.
    second = str(tmp_path / "second.blend")
    bpy.ops.wm.save_as_mainfile(filepath=second)
    scene = bpy.context.scene
    assert scene.hapticut.work_id != first_id
    assert owner(scene) == second
    assert work_folder.built_folder(scene) is not None
    assert scene.hapticut_live.recording_path != first_recording
    assert os.path.isfile(scene.hapticut_live.recording_path)
    assert exports(tmp_path, "second")

    # The copy's cube made bone and moved down 3 mm (its top at 2 mm), rebuilt, stroked and
    # baked, all in its own folder: its knife rests on the bone; the first one's went through.
    body = bpy.data.objects["Body"]
    body.hapticut.material_preset = "bone"
    body.location.z -= 3.0
    build(scene)
    simulate_and_bake(scene)
    second_recording = scene.hapticut_live.recording_path
    assert ideal_path(frames)[-1] > 1.5
    assert baked_first[-1] < 0.5
    bpy.ops.wm.save_mainfile()

    # The original: its build and its stroke as they were, its bake the same.
    bpy.ops.wm.open_mainfile(filepath=first)
    scene = bpy.context.scene
    assert scene.hapticut.status == "built"
    assert scene.hapticut_live.recording_path == first_recording
    assert bpy.ops.hapticut.clear_bake() == {"FINISHED"}
    assert bpy.ops.hapticut.bake_recording() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert ideal_path(frames) == pytest.approx(baked_first)
    # The copy's recording is refused, naming both scenes' builds.
    with pytest.raises(RuntimeError) as refused:
        bpy.ops.hapticut.bake_recording(filepath=second_recording)
    message = str(refused.value)
    assert "second.blend's scene" in message and "not of this file's scene" in message
    assert scene.hapticut.build_hash[:8] in message
    assert "Simulate Stroke (or Record) again" in message

    # The Save Copy's file found its own folder, with the build.
    bpy.ops.wm.open_mainfile(filepath=copy)
    scene = bpy.context.scene
    assert scene.hapticut.work_id not in (first_id, "")
    assert scene.hapticut.status == "built", scene.hapticut.status
    assert owner(scene) == copy


def test_a_file_copied_outside_blender_says_so_and_forks_before_writing(addon, data_home, tmp_path):
    from addon.authoring import work_folder

    scene = cube_scene()
    build(scene)
    first = str(tmp_path / "first.blend")
    bpy.ops.wm.save_as_mainfile(filepath=first)
    clone = str(tmp_path / "clone.blend")
    shutil.copyfile(first, clone)

    bpy.ops.wm.open_mainfile(filepath=clone)
    scene = bpy.context.scene
    first_id = scene.hapticut.work_id
    assert work_folder.shared_with(scene) == first
    assert scene.hapticut.status.startswith("built; the work folder is also")
    assert first in scene.hapticut.status and "Fork Work Folder" in scene.hapticut.status
    # Tetrahedralize (unchanged) writes into the folder: it forks first, the build shared.
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    assert scene.hapticut.status == "unchanged: not rebuilt"
    assert scene.hapticut.work_id != first_id
    assert owner(scene) == clone
    assert work_folder.shared_with(scene) is None

    # The original still owns its folder; a second clone forks through the operator.
    bpy.ops.wm.open_mainfile(filepath=first)
    assert bpy.context.scene.hapticut.work_id == first_id
    assert owner(bpy.context.scene) == first
    assert bpy.context.scene.hapticut.status == "built"
    other = str(tmp_path / "other.blend")
    shutil.copyfile(first, other)
    bpy.ops.wm.open_mainfile(filepath=other)
    assert bpy.ops.hapticut.fork_work_folder() == {"FINISHED"}
    scene = bpy.context.scene
    assert scene.hapticut.work_id != first_id
    assert scene.hapticut.status == "built"
    assert json.loads(scene.hapticut.report_json)["tets"] > 0
    assert exports(tmp_path, "forked")


def test_a_moved_file_takes_its_folder(addon, data_home, tmp_path):
    """The owner's file gone (moved outside Blender): the folder is the moved file's."""
    scene = cube_scene()
    bpy.ops.hapticut.check_scene()  # Anything that writes gives the scene its folder.
    bpy.ops.hapticut.wait()
    before = str(tmp_path / "before.blend")
    bpy.ops.wm.save_as_mainfile(filepath=before)
    work_id = bpy.context.scene.hapticut.work_id
    assert owner(bpy.context.scene) == before
    after = str(tmp_path / "after.blend")
    os.replace(before, after)
    bpy.ops.wm.open_mainfile(filepath=after)
    scene = bpy.context.scene
    assert "also" not in scene.hapticut.status
    bpy.ops.wm.save_mainfile()
    assert scene.hapticut.work_id == work_id
    assert owner(scene) == after


def test_a_build_running_through_save_as_lands_in_the_new_files_folder(addon, data_home, tmp_path):
    from addon.authoring import building, work_folder

    scene = cube_scene()
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "first.blend"))
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    started_in = work_folder.existing_work_directory(scene)
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "second.blend"))
    assert work_folder.existing_work_directory(scene) != started_in
    while building.update(scene.name):
        time.sleep(0.1)
    assert scene.hapticut.status.startswith("built"), scene.hapticut.error
    assert work_folder.built_folder(scene) == work_folder.build_folder(scene)
    assert exports(tmp_path, "second")
