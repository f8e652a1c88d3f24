"""Undo never strands (docs/addon.md, "Undo"): after an undo, Tetrahedralize rebuilds or shows
the build on disk (its preview and report, read from disk), and Bake bakes only a recording of
the scene's current build.

Real undo steps: the add-on's own (undo_steps.push) are pushed only where a window manager
keeps an undo stack, so the tests push one where the GUI would have one (after the timer's
preview or bake, after an edit in a panel) and undo with ``bpy.ops.ed.undo``."""

import json
import shutil

import bpy
import pytest
from file_scenes import build, cube_scene, simulate_and_bake

PREVIEW = "Hapticut Preview"


def step(name: str) -> None:
    assert bpy.ops.ed.undo_push(message=name) == {"FINISHED"}


def undo() -> object:
    assert bpy.ops.ed.undo() == {"FINISHED"}
    return bpy.context.scene  # The undo replaced Blender's data: look the scene up again.


def test_an_undone_rebuild_shows_the_build_on_disk(addon, data_home):
    from addon.authoring import work_folder

    scene = cube_scene()
    build(scene)
    step("Tetrahedralize preview")
    first_report = scene.hapticut.report_json
    # The build removed and made again from the same inputs: fTetWild's new tets.
    shutil.rmtree(work_folder.build_folder(scene))
    build(scene)
    step("Tetrahedralize preview")
    rebuilt = json.loads(scene.hapticut.report_json)
    scene = undo()
    assert scene.hapticut.report_json == first_report  # What the undo brought back.
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    assert scene.hapticut.status == "unchanged: not rebuilt"
    assert json.loads(scene.hapticut.report_json) == rebuilt
    assert len(bpy.data.collections[PREVIEW].objects) > 0


def test_a_deleted_preview_comes_back(addon, data_home):
    scene = cube_scene()
    build(scene)
    report = scene.hapticut.report_json
    collection = bpy.data.collections[PREVIEW]
    for obj in list(collection.objects):
        bpy.data.objects.remove(obj)
    bpy.data.collections.remove(collection)
    scene.hapticut.report_json = ""
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    assert scene.hapticut.status == "unchanged: not rebuilt"
    assert len(bpy.data.collections[PREVIEW].objects) > 0
    assert json.loads(scene.hapticut.report_json) == json.loads(report)


def test_bake_after_undo_bakes_only_the_current_builds_recording(addon, data_home):
    scene = cube_scene()
    build(scene)
    simulate_and_bake(scene)
    step("Bake stroke")
    first_digest = scene.hapticut.build_hash
    # An edit, a rebuild, a new stroke (the recording's path is the same file).
    bpy.data.objects["Body"].hapticut.material_preset = "fat"
    step("Material")
    build(scene)
    step("Tetrahedralize preview")
    simulate_and_bake(scene)
    step("Bake stroke")

    # Undo the bake, then the preview: the scene names the first build, not the one on disk.
    scene = undo()
    assert scene.hapticut.build_hash != first_digest
    scene = undo()
    assert scene.hapticut.build_hash == first_digest
    with pytest.raises(RuntimeError, match=r"is not the one on disk .* Tetrahedralize"):
        bpy.ops.hapticut.bake_recording()
    # Undo the edit too, and build: the stroke on disk is the fat cube's, refused by name.
    scene = undo()
    assert bpy.data.objects["Body"].hapticut.material_preset == "soft_tissue"
    build(scene)
    with pytest.raises(RuntimeError) as refused:
        bpy.ops.hapticut.bake_recording()
    assert "not of this file's scene" in str(refused.value)
    assert scene.hapticut.build_hash[:8] in str(refused.value)
    # A stroke of this build bakes.
    assert simulate_and_bake(scene)["frames"] > 1
