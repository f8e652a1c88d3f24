"""Helpers of the live tests: the finger built through the add-on once per test session, a
keyframed knife stroke, and following the servo by calling the live timer."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import blender_scene
import bpy

HERE = Path(__file__).resolve().parent
# The keyframed stroke (mm, frames at 24 fps) of the knife (its 40 mm edge along x, centred
# on its origin): above the finger, its edge over the proximal bone (x -36 to -9) and the
# flesh beyond; down into the bone (its surface is 3.5 mm from the axis), then across and
# out. The skin is a membrane that gives way at 0.5 N a point (a 5 mm lag at 0.1 N/mm; the
# preset's breaks sooner).
KNIFE_X = -22.0
DEEPEST_Z = -3.0
SKIN_BREAK_FORCE_N = 0.5
STROKE = ((1, (KNIFE_X, 0, 20)), (18, (KNIFE_X, 0, DEEPEST_Z)), (48, (KNIFE_X, 18, DEEPEST_Z)))
OVER_BONE_X = (-31.0, -14.0)  # Clear of its rounded ends.
_built: dict = {}


def build(scene, timeout_s: float = 900.0) -> None:
    from addon.authoring import building

    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    began = time.perf_counter()
    while building.update(scene.name):
        assert time.perf_counter() - began < timeout_s, "the build did not end"
        time.sleep(0.1)
    assert scene.hapticut.error == "", scene.hapticut.error


def keyframe_stroke(obj, stroke=STROKE, scale: float = 1.0) -> None:
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = 24, 1.0
    scene.frame_start, scene.frame_end = stroke[0][0], stroke[-1][0]
    for frame, location in stroke:
        obj.location = [c * scale for c in location]
        obj.keyframe_insert("location", frame=frame)


def finger_with_stroke(work: Path):
    """The finger scene (skin, flesh, bone, knife), built, the knife keyframed. Built once
    per test session and saved; later calls reopen that .blend."""
    if "blend" in _built:
        bpy.ops.wm.open_mainfile(filepath=_built["blend"])
        return bpy.context.scene
    scene = blender_scene.finger_scene(str(work))
    skin = bpy.data.objects["Skin"]
    skin.hapticut.custom_model, skin.hapticut.custom_name = "membrane", "skin"
    with bpy.context.temp_override(object=skin, active_object=skin):
        assert bpy.ops.hapticut.set_custom_material() == {"FINISHED"}
    skin.hapticut.custom_parameters["break_force_N"].value = SKIN_BREAK_FORCE_N
    scene.hapticut_live.realtime = False  # Shared test machines: no SCHED_FIFO.
    build(scene)
    keyframe_stroke(bpy.data.objects["Knife"])
    _built["work"] = work
    _built["blend"] = str(work / "finger-live_link.blend")
    bpy.ops.wm.save_as_mainfile(filepath=_built["blend"])
    return scene


def follow(until, timeout_s: float = 60.0, sleep_s: float = 0.005) -> float:
    """Call the live timer (as bpy.app.timers would) until ``until()``; seconds taken."""
    from addon.live import live_link

    began = time.perf_counter()
    while not until():
        live_link.timer()
        assert time.perf_counter() - began < timeout_s, "timed out following the servo"
        time.sleep(sleep_s)
    return time.perf_counter() - began


def probe_materials(scene_path: str, points, cut: bool = False) -> list[str]:
    """The model of the tet at each point (mm), by the toolkit in a child Python: "" outside.
    cut: a point on a face between a cuttable tet and another counts as cuttable (tet_probe)."""
    return _probe(scene_path, points, ["--cut"] if cut else [])


def bone_depths(scene_path: str, points) -> list[float]:
    """How deep each point (mm) is in rigid material (its distance to the bone's surface; 0
    outside), by the toolkit in a child Python (tet_probe)."""
    return _probe(scene_path, points, ["--depth"])


def _probe(scene_path: str, points, options: list[str]) -> list:
    done = subprocess.run(
        [sys.executable, str(HERE / "tet_probe.py"), scene_path, *options],
        input=json.dumps([list(map(float, p)) for p in points]),
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout)
