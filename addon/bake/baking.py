"""Bake a servo recording into the scene: per blade, the ideal blade keyframed at every frame,
a force arrow, and the cut surface revealed over time (docs/addon.md). Clear removes it all.

Everything comes from the recording (``hapticut.recording``) and the build's preview (its tets,
for the cut surface: ``hapticut.cut_surface``), never from the live stream.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import time

import bpy
import mathutils
import numpy as np

from ..background import steps
from ..live.stroke_path import frames_per_second, object_fcurves
from ..toolkit import runner
from ..toolkit.runner import last_error_line
from ..toolkit.toolkit_link import ToolkitLink
from ..toolkit.units import mm_per_unit
from . import cut_reveal, cut_slit

COLLECTION = "Hapticut Bake"
TAG = "hapticut_bake"
ARROW_MESH = "Hapticut Arrow"
CUT_COLOUR = (0.75, 0.05, 0.05, 1.0)
ARROW_COLOUR = (1.0, 0.75, 0.05, 1.0)
# Automatic arrow length (*Arrow length* 0): the stroke's peak force spans this fraction of the
# scene's diagonal, so the arrow reads on any scene size without covering it.
ARROW_SCENE_FRACTION = 0.2
# The longest a keying step runs before it lets Blender draw.
STEP_S = 0.02
# The most the cut surfaces' child may take (a long stroke through a large scene).
CUT_TIMEOUT_S = 600.0


class BakeError(RuntimeError):
    """The recording cannot be baked; the message says why."""


def _collection(scene):
    collection = bpy.data.collections.get(COLLECTION)
    if collection is None:
        collection = bpy.data.collections.new(COLLECTION)
    if collection.name not in scene.collection.children:
        scene.collection.children.link(collection)
    return collection


def _material(name: str, colour) -> bpy.types.Material:
    material = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    material.diffuse_color = colour
    if bpy.app.version < (5, 0, 0):  # Always true from 5.0 on (and deprecated there).
        material.use_nodes = True
    shader = material.node_tree.nodes.get("Principled BSDF")
    if shader is not None:
        shader.inputs["Base Color"].default_value = colour
        shader.inputs["Roughness"].default_value = 0.4
    return material


def _new_object(collection, name: str, data):
    obj = bpy.data.objects.new(name, data)
    obj[TAG] = 1
    collection.objects.link(obj)
    return obj


def _arrow_mesh(mm: float):
    """An arrow along +Z, 1 unit long (shaft 0.8, head 0.2), 0.4 mm thick at the shaft and
    1 mm at the head whatever its length (it is scaled along Z only)."""
    mesh = bpy.data.meshes.get(ARROW_MESH)
    if mesh is not None:
        return mesh
    sides = 12
    angles = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    ring = np.stack([np.cos(angles), np.sin(angles), np.zeros(sides)], 1) / mm
    vertices = np.concatenate(
        [ring * 0.2, ring * 0.2 + [0, 0, 0.8], ring * 0.5 + [0, 0, 0.8], [[0, 0, 1.0], [0, 0, 0]]]
    )
    faces = []
    for i in range(sides):
        j = (i + 1) % sides
        faces.append((i, j, sides + j, sides + i))  # shaft
        faces.append((2 * sides + i, 2 * sides + j, 3 * sides))  # head
        faces.append((j, i, 3 * sides + 1))  # base
        faces.append((sides + i, sides + j, 2 * sides + j, 2 * sides + i))  # shoulder
    mesh = bpy.data.meshes.new(ARROW_MESH)
    mesh.from_pydata(vertices.tolist(), [], faces)
    mesh.update()
    mesh.materials.append(_material("Hapticut Force", ARROW_COLOUR))
    return mesh


def _keyframes_steps(name: str, frames, values: dict) -> steps.Steps[None]:
    """Keyframes of the object called name at the frames (values: path -> (frames, k)
    array), linear between them, in steps of at most STEP_S. Each key's interpolation is set:
    the preference for new keys is not honoured by keyframe_insert from Python in every
    Blender version."""
    began = time.perf_counter()
    obj = _object_named(name)
    for k, frame in enumerate(frames):
        for path, array in values.items():
            setattr(obj, path, array[k])
            obj.keyframe_insert(path, frame=float(frame))
        if time.perf_counter() - began > STEP_S and k + 1 < len(frames):
            yield f"keying {name}, frame {int(frame)} of {int(frames[-1])}"
            began = time.perf_counter()
            obj = _object_named(name)
    for curve in object_fcurves(obj):
        for key in curve.keyframe_points:
            key.interpolation = "LINEAR"
        curve.update()


def _object_named(name: str):
    """A baked object, looked up again after a step (an undo in between replaces it)."""
    obj = bpy.data.objects.get(name)
    if obj is None:
        raise BakeError(f"the baked object {name!r} is gone: bake again")
    return obj


def scene_diagonal_mm(tets: dict) -> float:
    """The diagonal (mm) of the box of the scene's material, the air around it left out."""
    solid = [i for i, model in enumerate(tets["models"]) if model != "free"]
    chosen = np.isin(tets["materials"], solid)
    corners = tets["tets"][chosen] if chosen.any() else tets["tets"]
    points = np.asarray(tets["vertices"], np.float64)[np.unique(corners)]
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0))) if len(points) else 0.0


def arrow_mm_per_N(setting: float, peak_force_N: float, diagonal_mm: float) -> float:
    """The setting when it is above 0; else the scale at which the peak force's arrow spans
    ARROW_SCENE_FRACTION of the scene's diagonal (1 mm/N for a scene without force)."""
    if setting > 0:
        return float(setting)
    if peak_force_N <= 0 or diagonal_mm <= 0:
        return 1.0
    return ARROW_SCENE_FRACTION * diagonal_mm / peak_force_N


def cut_mesh(name: str, surface, mm: float, slit_mm: float = 0.0):
    """The cut surface's mesh (Blender units), as a slit of half-width slit_mm (cut_slit)."""
    mesh = bpy.data.meshes.new(name)
    vertices, faces, face_frames = cut_slit.slit(
        surface.vertices, surface.faces, surface.face_frames, slit_mm
    )
    vertices = vertices / mm
    mesh.vertices.add(len(vertices))
    mesh.vertices.foreach_set("co", vertices.astype(np.float32).ravel())
    mesh.loops.add(3 * len(faces))
    mesh.loops.foreach_set("vertex_index", faces.astype(np.int32).ravel())
    mesh.polygons.add(len(faces))
    mesh.polygons.foreach_set("loop_start", np.arange(0, 3 * len(faces), 3, dtype=np.int32))
    mesh.update(calc_edges=True)
    # Smooth across the swept surface's triangles (cut_slit.slit_normals), not flat per face.
    mesh.polygons.foreach_set("use_smooth", np.ones(len(faces), bool))
    normals = cut_slit.slit_normals(surface.vertices, surface.faces)
    mesh.normals_split_custom_set(normals.reshape(-1, 3).tolist())
    attribute = mesh.attributes.new(cut_reveal.FRAME_ATTRIBUTE, "INT", "FACE")
    attribute.data.foreach_set("value", np.asarray(face_frames, np.int32))
    mesh.materials.append(_material("Hapticut Cut", CUT_COLOUR))
    return mesh


def blade_half_thickness_mm(name: str, mm: float) -> float:
    """Half the thickness of the blade object's mesh in the world (its scale applied), in mm;
    0 when the blade is gone or not a mesh."""
    blade = bpy.data.objects.get(name)
    if blade is None or blade.type != "MESH" or not len(blade.data.vertices):
        return 0.0
    vertices = np.empty((len(blade.data.vertices), 3))
    blade.data.vertices.foreach_get("co", vertices.ravel())
    scaled = vertices @ np.array(blade.matrix_world.to_3x3()).T
    return cut_slit.half_thickness(scaled) * mm


def load_preview_tets(link: ToolkitLink, path: str) -> dict:
    try:
        return link.preview_tets(path)
    except (OSError, KeyError, ValueError) as error:
        raise BakeError(
            f"the scene's tets cannot be read from {path} ({error}): tetrahedralize again"
        ) from None


def ideal_poses(recording, name: str, ticks) -> list[tuple[mathutils.Vector, mathutils.Quaternion]]:
    """The ideal blade's pose (mm) at each of the ticks (``Recording.placed_poses``)."""
    return [
        (mathutils.Vector(pose[:3]), mathutils.Quaternion(pose[3:7]))
        for pose in recording.placed_poses(name, ticks)
    ]


def bake_steps(
    scene_name: str, link: ToolkitLink, recording_path: str, preview_path: str
) -> steps.Steps[dict]:
    """Bake the recording (module doc) in steps; its figures for the panel. Clears an earlier
    bake."""
    began = time.perf_counter()

    def scene_now():
        scene = bpy.data.scenes.get(scene_name)
        if scene is None:
            raise BakeError(f"the scene {scene_name!r} is gone")
        return scene

    try:
        recording = link.read_recording(recording_path)
    except (OSError, ValueError) as error:
        raise BakeError(str(error)) from None
    if len(recording) < 2:
        raise BakeError(
            f"recording {recording_path} holds {len(recording)} tick(s): nothing to bake"
        )
    yield "reading the scene's tets"
    tets = load_preview_tets(link, preview_path)
    yield "placing the keys"
    scene = scene_now()
    live = scene.hapticut_live
    mm = mm_per_unit(scene)
    fps = frames_per_second(scene)
    frame_start, frame_end = scene.frame_start, scene.frame_end
    substeps, arrow_setting = live.substeps, live.arrow_mm_per_N
    times = recording.elapsed_s()
    # The keys stay in the scene's frame range; what the recording holds after it (a Simulate
    # stroke's stop ramp, a longer live recording) is not baked, and the report says so.
    frames, nearest = link.frame_ticks(times, fps, frame_start, frame_end)
    if not len(frames):
        raise BakeError(
            f"the scene's frame range {frame_start}-{frame_end} is empty: nothing to bake"
        )
    baked_ticks = int(nearest[-1]) + 1
    forces_by_blade = {
        name: recording.blade(name)["block"]["engine_force_N"][nearest]
        for name in recording.blade_names
    }
    peak_force_N = max(
        (float(np.max(np.linalg.norm(f, axis=1))) for f in forces_by_blade.values()), default=0.0
    )
    diagonal_mm = scene_diagonal_mm(tets)
    mm_per_N = arrow_mm_per_N(arrow_setting, peak_force_N, diagonal_mm)
    figures = _bake_figures(link, recording, recording_path, times, frames, fps, mm_per_N)
    folder = tempfile.mkdtemp(prefix="hapticut-cut-")
    cuts_path = os.path.join(folder, "cuts.npz")
    # A child computes the cut surfaces while the keys are placed.
    cutting = None
    try:
        cutting = steps.started(
            _cut_child(link.executable, recording_path, preview_path, cuts_path, fps,
                       frame_start, substeps, baked_ticks)
        )  # fmt: skip
        yield "clearing the last bake"
        scene = scene_now()
        clear(scene)
        _collection(scene)
        for name in recording.blade_names:
            yield from _key_blade_steps(
                scene_now, recording, name, frames, nearest, forces_by_blade[name], mm, mm_per_N
            )
        done = yield from cutting
        if done.returncode != 0:
            line = last_error_line(done.stderr)
            raise BakeError(f"the cut surfaces were not computed: {line}")
        try:
            surfaces = link.read_cut_surfaces(cuts_path)
        except (OSError, KeyError, ValueError) as error:
            raise BakeError(f"the cut surfaces cannot be read ({error})") from None
    finally:
        if cutting is not None:
            cutting.close()  # Kills the child when the bake ends early.
        shutil.rmtree(folder, ignore_errors=True)
    for name in recording.blade_names:
        yield f"meshing {name}'s cut"
        surface = surfaces[name]
        slit_mm = blade_half_thickness_mm(name, mm) + cut_slit.SLIT_SHARE * diagonal_mm
        cut = _new_object(
            _collection(scene_now()), f"Cut {name}", cut_mesh(f"Cut {name}", surface, mm, slit_mm)
        )
        cut["hapticut_blade"] = name
        cut_reveal.add_reveal(cut)
        figures["blades"][name] = {
            "cut_faces": len(surface.faces),
            "cut_slit_mm": slit_mm,
            "max_force_N": float(np.max(np.linalg.norm(forces_by_blade[name], axis=1))),
        }
    figures["seconds"] = time.perf_counter() - began
    live = scene_now().hapticut_live
    live.bake_report = json.dumps(figures)
    live.recording_path = recording_path
    return figures


def _bake_figures(
    link: ToolkitLink,
    recording,
    recording_path: str,
    times: np.ndarray,
    frames: np.ndarray,
    fps: float,
    mm_per_N: float,
) -> dict:
    """What the panel reports of a bake before its blades are added (``figures["blades"]``):
    ``times`` are the records' (``Recording.elapsed_s``), ``frames`` the keyed ones."""
    covered = link.covered_steps(times, 1.0 / fps)
    last_frame_s = (frames[-1] - frames[0]) / fps
    return {
        "recording": recording_path,
        "ticks": len(recording),
        "frames": len(frames),
        "frame_range": [int(frames[0]), int(frames[-1])],
        # The frames the recording covers after frame_end (not baked), and their seconds.
        "unbaked_frames": covered - len(frames),
        "unbaked_s": float(times[-1] - last_frame_s) if covered > len(frames) else 0.0,
        "arrow_mm_per_N": mm_per_N,
        "dropped_records": int(recording.ticks["dropped_records"][-1]),
        # A cut recording bakes its whole records; the panel says it was cut.
        "truncated": recording.problem,
        "blades": {},
    }


def _cut_child(
    executable: str,
    recording_path: str,
    preview_path: str,
    out: str,
    fps: float,
    frame_start: int,
    substeps: int,
    ticks: int,
) -> steps.Steps[steps.ChildResult]:
    """``hapticut cut-surface``: the cut surfaces of the recording's first ticks, into out."""
    command = [executable, "cut-surface", recording_path, preview_path, "--out", out]
    command += ["--fps", repr(float(fps)), "--frame-start", str(frame_start)]
    command += ["--substeps", str(substeps), "--ticks", str(max(ticks, 2))]
    try:
        return (
            yield from steps.child(
                command, CUT_TIMEOUT_S, "cutting the surfaces", runner.child_environment()
            )
        )
    except (OSError, steps.ChildTimeoutError) as error:
        raise BakeError(f"the cut surfaces were not computed: {error}") from None


def _key_blade_steps(
    scene_now, recording, name: str, frames, nearest, forces, mm: float, mm_per_N: float
) -> steps.Steps[None]:
    """The blade's ideal blade and its force arrow, keyed at the frames."""
    blade = recording.blade(name)
    source = bpy.data.objects.get(name)
    placed = ideal_poses(recording, name, nearest)
    locations = [location / mm for location, _ in placed]
    rotations = [rotation for _, rotation in placed]
    centres = [mathutils.Vector(blade["q"][k].mean(axis=0)) / mm for k in nearest]
    ideal = _new_object(_collection(scene_now()), f"Ideal {name}", source.data if source else None)
    ideal["hapticut_blade"] = name
    ideal.rotation_mode = "QUATERNION"
    if source is not None:
        ideal.scale = source.matrix_world.to_scale()
    yield from _keyframes_steps(
        ideal.name, frames, {"location": locations, "rotation_quaternion": rotations}
    )
    # The force arrow at the proxies' centre.
    arrow = _new_object(_collection(scene_now()), f"Force {name}", _arrow_mesh(mm))
    arrow["hapticut_blade"] = name
    arrow.rotation_mode = "QUATERNION"
    lengths = np.linalg.norm(forces, axis=1) * mm_per_N / mm
    z = mathutils.Vector((0, 0, 1))
    arrow_rotations = [
        z.rotation_difference(mathutils.Vector(f))
        if np.linalg.norm(f) > 0
        else mathutils.Quaternion()
        for f in forces
    ]
    # Zero force: a flat arrow (hidden), never a zero scale.
    scales = [
        mathutils.Vector((1.0, 1.0, max(s, 1e-6))) if s > 0 else mathutils.Vector((1e-6,) * 3)
        for s in lengths
    ]
    yield from _keyframes_steps(
        arrow.name,
        frames,
        {"location": centres, "rotation_quaternion": arrow_rotations, "scale": scales},
    )


def baked_objects() -> list:
    """Every object a bake made, in any scene (their collection is shared)."""
    return [o for o in bpy.data.objects if o.get(TAG)]


def clear(scene) -> int:
    """Remove every object a bake made, their meshes (not a blade's), actions and the
    collection; the number of objects removed."""
    removed = 0
    for obj in baked_objects():
        data = obj.data
        action = obj.animation_data.action if obj.animation_data else None
        bpy.data.objects.remove(obj)
        removed += 1
        if action is not None and action.users == 0:
            bpy.data.actions.remove(action)
        if isinstance(data, bpy.types.Mesh) and data.users == 0:
            bpy.data.meshes.remove(data)
    collection = bpy.data.collections.get(COLLECTION)
    if collection is not None and not collection.objects:
        bpy.data.collections.remove(collection)
    group = bpy.data.node_groups.get(cut_reveal.GROUP_NAME)
    if group is not None and group.users == 0:
        bpy.data.node_groups.remove(group)
    if scene is not None:
        scene.hapticut_live.bake_report = ""
    return removed
