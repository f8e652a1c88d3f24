"""A blade's keyframed animation as the sim device's path (docs/servo.md, ``sim:PATH``).

The path is one pose per servo tick, from the scene's first frame to its last: the blade
object's world pose (origin in mm, rotation as a unit quaternion; its scale is in the cutting
edge already, exchange.blade_edge_mm). An object animated by its own F-curves alone (no
parent, no constraints) is evaluated from the F-curves at every tick; any other is evaluated
by the scene at every frame and ``SUBFRAMES`` subframes, and the servo interpolates between.
"""

from __future__ import annotations

import json
import os
import time

import bpy
import mathutils
import numpy as np

from ..background import steps
from ..toolkit.units import mm_per_unit

SUBFRAMES = 4
# The longest a step of the sampling runs before it lets Blender draw.
STEP_S = 0.02
TRANSFORM_PATHS = (
    "location",
    "rotation_euler",
    "rotation_quaternion",
    "rotation_axis_angle",
    "scale",
    "delta_location",
    "delta_rotation_euler",
    "delta_rotation_quaternion",
    "delta_scale",
)


def frames_per_second(scene) -> float:
    return scene.render.fps / scene.render.fps_base


def object_fcurves(obj) -> list:
    """The F-curves animating the object (Blender 4.2 actions and 4.4+ slotted actions)."""
    animation = obj.animation_data
    action = animation.action if animation is not None else None
    if action is None:
        return []
    slot = getattr(animation, "action_slot", None)
    if slot is not None:
        try:
            from bpy_extras import anim_utils

            channelbag = anim_utils.action_get_channelbag_for_slot(action, slot)
            return list(channelbag.fcurves) if channelbag is not None else []
        except (ImportError, AttributeError):
            pass
    return list(getattr(action, "fcurves", ()))


def _own_curves_only(obj) -> bool:
    return (
        obj.parent is None
        and not obj.constraints
        and all(c.data_path in TRANSFORM_PATHS for c in object_fcurves(obj))
        and not (obj.animation_data and obj.animation_data.drivers)
    )


def pose_of(matrix, mm: float) -> list[float]:
    """[x, y, z (mm), qw, qx, qy, qz] of a world matrix (its scale dropped)."""
    location, rotation, _ = matrix.decompose()
    rotation.normalize()
    return [
        location.x * mm,
        location.y * mm,
        location.z * mm,
        rotation.w,
        rotation.x,
        rotation.y,
        rotation.z,
    ]


def _matrix_from_curves(obj, curves: dict, frame: float):
    def value(path, index, default):
        curve = curves.get((path, index))
        return curve.evaluate(frame) if curve is not None else default

    location = mathutils.Vector([value("location", i, obj.location[i]) for i in range(3)])
    location += mathutils.Vector(
        [value("delta_location", i, obj.delta_location[i]) for i in range(3)]
    )
    mode = obj.rotation_mode
    if mode == "QUATERNION":
        rotation = mathutils.Quaternion(
            [value("rotation_quaternion", i, obj.rotation_quaternion[i]) for i in range(4)]
        )
    elif mode == "AXIS_ANGLE":
        angle_axis = [value("rotation_axis_angle", i, obj.rotation_axis_angle[i]) for i in range(4)]
        rotation = mathutils.Quaternion(mathutils.Vector(angle_axis[1:]), angle_axis[0])
    else:
        euler = mathutils.Euler(
            [value("rotation_euler", i, obj.rotation_euler[i]) for i in range(3)], mode
        )
        rotation = euler.to_quaternion()
    delta = mathutils.Euler(
        [value("delta_rotation_euler", i, obj.delta_rotation_euler[i]) for i in range(3)],
        obj.rotation_mode if obj.rotation_mode not in ("QUATERNION", "AXIS_ANGLE") else "XYZ",
    ).to_quaternion()
    rotation = rotation @ delta
    return mathutils.Matrix.LocRotScale(location, rotation, None)


def sample_poses_steps(scene_name: str, name: str, rate_Hz: float) -> steps.Steps[np.ndarray]:
    """(K, 8): [t_s, x, y, z, qw, qx, qy, qz] of the object called name from frame_start to
    frame_end, as steps of at most STEP_S each (the scene and the object are looked up again
    after each)."""

    def objects():
        scene = bpy.data.scenes.get(scene_name)
        obj = scene.objects.get(name) if scene is not None else None
        if obj is None:
            raise RuntimeError(f"the blade {name!r} of scene {scene_name!r} is gone")
        return scene, obj

    scene, obj = objects()
    mm = mm_per_unit(scene)
    fps = frames_per_second(scene)
    first, last = scene.frame_start, max(scene.frame_end, scene.frame_start)
    duration = (last - first) / fps
    rows = []
    step_began = time.perf_counter()
    if _own_curves_only(obj):
        count = int(np.floor(duration * rate_Hz + 1e-9)) + 1
        k = 0
        while k < count:
            scene, obj = objects()
            curves = {(c.data_path, c.array_index): c for c in object_fcurves(obj)}
            while k < count and time.perf_counter() - step_began < STEP_S:
                t = k / rate_Hz
                rows.append([t, *pose_of(_matrix_from_curves(obj, curves, first + t * fps), mm)])
                k += 1
            if k < count:
                yield f"sampling {name}'s stroke, {k} of {count} ticks"
                step_began = time.perf_counter()
    else:
        current = scene.frame_current, scene.frame_subframe
        steps_count = (last - first) * SUBFRAMES
        k = 0
        try:
            while k <= steps_count:
                scene, obj = objects()
                while k <= steps_count and time.perf_counter() - step_began < STEP_S:
                    frame = first + k / SUBFRAMES
                    scene.frame_set(int(np.floor(frame)), subframe=frame - np.floor(frame))
                    rows.append([(frame - first) / fps, *pose_of(obj.matrix_world, mm)])
                    k += 1
                if k <= steps_count:
                    yield f"sampling {name}'s stroke, frame {first + k // SUBFRAMES} of {last}"
                    step_began = time.perf_counter()
        finally:
            scene = bpy.data.scenes.get(scene_name)
            if scene is not None:
                scene.frame_set(current[0], subframe=current[1])
    poses = np.array(rows, np.float64)
    # Keep the quaternions on one hemisphere (the servo interpolates between neighbours).
    for k in range(1, len(poses)):
        if np.dot(poses[k, 4:], poses[k - 1, 4:]) < 0:
            poses[k, 4:] *= -1
    return poses


def write_path(poses: np.ndarray, path: str) -> str:
    """The sim device's path file (``{"poses": [[t_s, x, y, z, qw, qx, qy, qz], ...]}``)."""
    if len(poses) == 1:  # A still blade: the sim path needs increasing times.
        poses = np.vstack([poses, poses])
        poses[1, 0] = poses[0, 0] + 1e-3
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path, "w", encoding="utf-8") as file:
        json.dump({"poses": poses.round(9).tolist()}, file)
    return path


def is_animated(obj) -> bool:
    return bool(object_fcurves(obj)) or obj.parent is not None or bool(obj.constraints)
