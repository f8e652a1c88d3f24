"""Building Blender scenes for the add-on's tests (bpy in background mode)."""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

import bpy
import numpy as np

REPO = Path(__file__).resolve().parents[3]
MESHES = REPO / "examples" / "meshes"
ADDON_MODULE = "addon"
# Coarse enough for a test (the skin is 1.5 mm thick: the envelope, 40% of the accuracy,
# must stay under it).
TEST_ACCURACY_MM = 1.5
TEST_EDGE_NEAR_MM = 5.0
TEST_EDGE_FAR_MM = 20.0


def toolkit_executable() -> str:
    """The hapticut command beside this Python, else on PATH (HAPTICUT_TOOLKIT overrides)."""
    configured = os.environ.get("HAPTICUT_TOOLKIT")
    if configured:
        return configured
    beside = Path(sys.executable).with_name("hapticut")
    if beside.exists():
        return str(beside)
    found = shutil.which("hapticut")
    assert found, "the hapticut toolkit is not installed"
    return found


def enable_addon():
    """The add-on enabled from its folder (the development install), its preferences set."""
    import addon_utils

    if str(REPO) not in sys.path:
        sys.path.insert(0, str(REPO))
    addon_utils.enable(ADDON_MODULE, default_set=True, handle_error=None)
    prefs = bpy.context.preferences.addons[ADDON_MODULE].preferences
    prefs.toolkit_path = toolkit_executable()
    bpy.ops.hapticut.check_toolkit()
    bpy.ops.hapticut.wait()
    return prefs


def disable_addon() -> None:
    import addon_utils

    addon_utils.disable(ADDON_MODULE, default_set=True, handle_error=None)


def empty_scene(work_dir: str):
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.unit_settings.scale_length = 0.001  # 1 Blender unit = 1 mm.
    scene.hapticut.work_directory = work_dir
    return scene


def read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    vertices, faces = [], []
    for line in path.read_text().splitlines():
        parts = line.split()
        if parts and parts[0] == "v":
            vertices.append([float(x) for x in parts[1:4]])
        elif parts and parts[0] == "f":
            # OBJ indices count from 1, or back from the last vertex when negative.
            indices = [int(p.split("/")[0]) for p in parts[1:4]]
            faces.append([i - 1 if i > 0 else len(vertices) + i for i in indices])
    return np.array(vertices), np.array(faces)


def mesh_object(name: str, vertices, faces, location=(0.0, 0.0, 0.0)):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(v) for v in vertices], [], [tuple(f) for f in faces])
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    return obj


def region(name: str, mesh_file: str, preset: str, scale: float = 1.0):
    vertices, faces = read_obj(MESHES / mesh_file)
    obj = mesh_object(name, vertices * scale, faces)
    obj.hapticut.role = "REGION"
    obj.hapticut.material_preset = preset
    return obj


def knife(name: str = "Knife", scale: float = 1.0):
    """A triangle whose first two vertices are its 40 mm cutting edge, 20 mm above the finger
    (scale: Blender units per mm)."""
    vertices = np.array([(-20, 0, 0), (20, 0, 0), (0, 0, 8)]) * scale
    obj = mesh_object(name, vertices, [(0, 1, 2)], location=(0, 0, 20 * scale))
    obj.hapticut.role = "BLADE"
    obj.hapticut.edge_vertex_a, obj.hapticut.edge_vertex_b = 0, 1
    obj.hapticut.blade_points = 20
    return obj


def finger_scene(work_dir: str, scale: float = 1.0):
    """Skin, flesh and one bone of the finger example, and a knife; the test's accuracy."""
    scene = empty_scene(work_dir)
    region("Skin", "finger_skin.obj", "skin", scale)
    region("Flesh", "finger_flesh.obj", "soft_tissue", scale)
    region("Bone", "finger_bone_proximal.obj", "bone", scale)
    knife(scale=scale)
    settings = scene.hapticut
    settings.accuracy = TEST_ACCURACY_MM * scale
    settings.edge_near = TEST_EDGE_NEAR_MM * scale
    settings.edge_far = TEST_EDGE_FAR_MM * scale
    return scene
