"""A small scene built through the add-on for the tests of files and folders: a soft cube and
the test knife keyframed down into it, *Work directory* left empty (the user's data folder,
moved into the test's temporary directory by conftest's ``data_home``)."""

import json
import os
import time

import blender_scene
import bpy
import live_support

STROKE = ((1, (0.0, 0.0, 20.0)), (12, (0.0, 0.0, 0.0)))  # The knife down into the cube.


def cube_scene(size_mm: float = 10.0):
    """A soft cube and the test knife over it, Work directory left empty."""
    scene = blender_scene.empty_scene("")
    vertices = [
        (x * size_mm / 2, y * size_mm / 2, z * size_mm / 2)
        for x in (-1, 1)
        for y in (-1, 1)
        for z in (-1, 1)
    ]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    body = blender_scene.mesh_object("Body", vertices, faces)
    body.hapticut.role = "REGION"
    body.hapticut.material_preset = "soft_tissue"
    knife = blender_scene.knife()
    live_support.keyframe_stroke(knife, STROKE)
    scene.hapticut_live.realtime = False  # Shared test machines: no SCHED_FIFO.
    scene.hapticut.accuracy = 1.0  # Coarse: the tests are about files, not meshes.
    scene.hapticut.edge_near = blender_scene.TEST_EDGE_NEAR_MM
    return scene


def build(scene) -> float:
    began = time.perf_counter()
    live_support.build(scene)
    assert scene.hapticut.status.startswith("built"), scene.hapticut.status
    return time.perf_counter() - began


def exports(tmp_path, name: str) -> bool:
    path = str(tmp_path / f"{name}.hapticut.msgpack")
    try:
        bpy.ops.hapticut.export_scene(filepath=path)
        bpy.ops.hapticut.wait()
    except RuntimeError as error:
        assert "no scene built yet" in str(error)
        return False
    return os.path.getsize(path) > 0


def simulate_and_bake(scene) -> dict:
    from addon.bake import baking
    from addon.live import live_link

    try:
        assert bpy.ops.hapticut.simulate_stroke() == {"FINISHED"}
        assert bpy.ops.hapticut.wait() == {"FINISHED"}
        assert scene.hapticut_live.error == ""
        assert baking.baked_objects()
        return json.loads(scene.hapticut_live.bake_report)
    finally:
        live_link.stop()
