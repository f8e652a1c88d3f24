"""The build follows its .blend: Save As and reopening keep it usable (Export, Simulate
stroke, Bake), the status after reopening is the build on disk's, a failed build clears the
old report, a build never lands in another file; and the undo steps (docs/addon.md, "The work
folder", "Undo").

The scenes leave *Work directory* empty (the default), with the user's data folder moved into
the test's temporary directory (XDG_DATA_HOME)."""

import json
import shutil
import time

import blender_scene
import bpy
from file_scenes import build, cube_scene, exports, simulate_and_bake


def test_save_as_and_reopen_keep_the_build(addon, data_home, tmp_path):
    scene = cube_scene()
    print(f"\ncube built in {build(scene):.1f} s")
    first = str(tmp_path / "first.blend")
    bpy.ops.wm.save_as_mainfile(filepath=first)
    assert exports(tmp_path, "first")
    # Save As under another name: the build is still the scene's.
    second = str(tmp_path / "second.blend")
    bpy.ops.wm.save_as_mainfile(filepath=second)
    assert exports(tmp_path, "second")
    baked = simulate_and_bake(scene)
    assert baked["frames"] > 1
    assert scene.hapticut_live.recording_path.startswith(str(data_home))
    bpy.ops.wm.save_mainfile()
    # Reopen: the status is true, Export and Bake (from the kept recording) work.
    bpy.ops.wm.read_homefile(use_empty=True)
    bpy.ops.wm.open_mainfile(filepath=second)
    scene = bpy.context.scene
    assert scene.hapticut.status == "built"
    assert json.loads(scene.hapticut.report_json)["tets"] > 0
    assert exports(tmp_path, "reopened")
    assert bpy.ops.hapticut.clear_bake() == {"FINISHED"}
    assert bpy.ops.hapticut.bake_recording() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert json.loads(scene.hapticut_live.bake_report)["frames"] == baked["frames"]
    # The first file (saved before the stroke) finds the same build.
    bpy.ops.wm.open_mainfile(filepath=first)
    assert bpy.context.scene.hapticut.status == "built"
    assert exports(tmp_path, "first-reopened")


def test_after_reopening_the_status_is_the_build_on_disk(addon, data_home, tmp_path):
    from addon.authoring import building

    scene = cube_scene()
    build(scene)
    # A second build, cancelled: the first one stays, and the status says so.
    bpy.data.objects["Body"].hapticut.material_preset = "fat"
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    assert building.cancel_build(scene.name)
    assert scene.hapticut.status == "cancelled: the last build stays"
    path = str(tmp_path / "cancelled.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    assert scene.hapticut.status == "built"
    assert not scene.hapticut.running
    assert exports(tmp_path, "kept")
    # The build removed from disk: the reopened file says so and shows no report.
    from addon.authoring import work_folder

    shutil.rmtree(work_folder.build_folder(scene))
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    assert scene.hapticut.status == work_folder.NO_BUILD_STATUS
    assert scene.hapticut.report_json == ""
    assert not exports(tmp_path, "gone")


def test_a_failed_build_clears_the_report(addon, data_home, tmp_path):
    from addon.authoring import build_job, building

    scene = cube_scene()
    build(scene)
    body = bpy.data.objects["Body"]
    faces = [tuple(p.vertices) for p in body.data.polygons]
    vertices = [v.co[:] for v in body.data.vertices]
    # One face less: the toolkit refuses the open mesh.
    body.data = bpy.data.meshes.new("Open")
    body.data.from_pydata(vertices, [], faces[1:])
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    while building.update(scene.name):
        time.sleep(0.05)
    assert scene.hapticut.status == "failed"
    assert scene.hapticut.error.startswith("Body: the mesh is open")
    assert scene.hapticut.report_json == ""
    assert not exports(tmp_path, "after-failure")
    # Closed again: the scene is the one on disk, shown again without a build.
    body.data = bpy.data.meshes.new("Closed")
    body.data.from_pydata(vertices, [], faces)
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    assert build_job.running(scene.name) is None
    assert scene.hapticut.status == "unchanged: not rebuilt"
    assert json.loads(scene.hapticut.report_json)["tets"] > 0
    assert exports(tmp_path, "closed-again")


def test_a_build_never_lands_in_the_next_file(addon, data_home, tmp_path):
    from addon.authoring import build_job

    other = str(tmp_path / "other.blend")
    blender_scene.empty_scene("")
    bpy.ops.wm.save_as_mainfile(filepath=other)
    scene = cube_scene()
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    job = build_job.running(scene.name)
    assert job is not None
    bpy.ops.wm.open_mainfile(filepath=other)
    assert build_job.running(bpy.context.scene.name) is None
    assert job.process.poll() is not None
    assert bpy.context.scene.hapticut.report_json == ""
    assert "Hapticut Preview" not in bpy.data.collections


def test_undo_steps(addon, data_home, monkeypatch):
    """Background mode has no undo stack (bpy.ops.ed.undo cannot run there): the options are
    checked, and the steps pushed where a timer edits the scene are recorded."""
    from addon.background import undo_steps

    for name in ("clear_bake", "set_cutting_edge"):
        options = getattr(bpy.types, f"HAPTICUT_OT_{name}").bl_options
        assert {"REGISTER", "UNDO"} <= set(options), name
    # Operators that start background work push no step of their own: the preview, the
    # import and the bakes come later, from a timer, which pushes one.
    for name in ("tetrahedralize", "simulate_stroke", "bake_recording", "import_scene"):
        options = getattr(getattr(bpy.types, f"HAPTICUT_OT_{name}"), "bl_options", set())
        assert "UNDO" not in options, name
    pushed = []
    monkeypatch.setattr(undo_steps, "push", pushed.append)
    scene = cube_scene()
    build(scene)
    assert pushed == ["Tetrahedralize preview"]
    simulate_and_bake(scene)
    assert pushed == ["Tetrahedralize preview", "Bake stroke"]
    assert bpy.ops.hapticut.bake_recording() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert pushed == ["Tetrahedralize preview", "Bake stroke", "Bake"]


def test_a_work_directory_relative_to_the_blend_is_taken_without_a_warning(addon, tmp_path):
    import warnings

    from addon.authoring import work_folder

    scene = blender_scene.empty_scene("")
    bpy.ops.wm.save_as_mainfile(filepath=str(tmp_path / "relative.blend"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # Blender 5.0 warns for a path without the option.
        scene.hapticut.work_directory = "//hapticut-work"
    assert work_folder.existing_work_directory(scene) == str(tmp_path / "hapticut-work")
