"""The Blender demo: a knife cuts a finger, from authoring to rendered pictures.

Builds a .blend with the finger (skin, flesh, three bones) and a knife with a keyframed
stroke, tetrahedralizes it through the add-on, runs the stroke through the servo (Simulate
stroke: as fast as possible, recorded), bakes it (the ideal blade, the force arrow, the cut
surface opening frame by frame) and renders PNG frames with Cycles on the CPU plus one
contact sheet, then prints each stage's time and a summary of the stroke (forces, the points'
states) read from the servo's recording. Runs in Python with the ``bpy`` module (background
mode); the README's demo command (examples/demo.sh) installs what it needs first.

    python3 examples/blender_demo.py [--quick | --no-render] [--out build/blender-demo]
                                     [--sheet docs/blender_demo.png]
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import time
from pathlib import Path

import bpy
import numpy as np

REPO = Path(__file__).resolve().parents[1]
MESHES = REPO / "examples" / "meshes"
FPS = 24
KNIFE_X = -22.0  # Its 40 mm edge over the proximal bone (x -36 to -9) and the joint.


def toolkit_executable() -> str:
    """The hapticut command beside this Python, else on PATH (HAPTICUT_TOOLKIT overrides, as
    in the add-on's tests: a toolkit under development renders without installing it)."""
    if os.environ.get("HAPTICUT_TOOLKIT"):
        return os.environ["HAPTICUT_TOOLKIT"]
    beside = Path(sys.executable).with_name("hapticut")
    found = str(beside) if beside.exists() else shutil.which("hapticut")
    if not found:
        sys.exit("blender_demo: the hapticut toolkit is not installed (bash examples/demo.sh)")
    return found


def enable_addon() -> None:
    import addon_utils

    sys.path.insert(0, str(REPO))
    addon_utils.enable("addon", default_set=True, handle_error=None)
    prefs = bpy.context.preferences.addons["addon"].preferences
    prefs.toolkit_path = toolkit_executable()
    assert bpy.ops.hapticut.check_toolkit() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}


def read_obj(path: Path):
    vertices, faces = [], []
    for line in path.read_text().splitlines():
        parts = line.split()
        if parts and parts[0] == "v":
            vertices.append([float(x) for x in parts[1:4]])
        elif parts and parts[0] == "f":
            indices = [int(p.split("/")[0]) for p in parts[1:]]
            faces.append([i - 1 if i > 0 else len(vertices) + i for i in indices])
    return vertices, faces


def mesh_object(name: str, vertices, faces, collection=None):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices, [], faces)
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    (collection or bpy.context.scene.collection).objects.link(obj)
    return obj


def material(name: str, colour, alpha: float = 1.0, emission: float = 0.0, roughness=0.5):
    mat = bpy.data.materials.new(name)
    if bpy.app.version < (5, 0, 0):
        mat.use_nodes = True
    shader = mat.node_tree.nodes["Principled BSDF"]
    shader.inputs["Base Color"].default_value = (*colour, 1.0)
    shader.inputs["Alpha"].default_value = alpha
    shader.inputs["Roughness"].default_value = roughness
    if emission:
        shader.inputs["Emission Color"].default_value = (*colour, 1.0)
        shader.inputs["Emission Strength"].default_value = emission
    mat.diffuse_color = (*colour, alpha)
    return mat


def region(name: str, mesh_file: str, preset: str, look):
    obj = mesh_object(name, *read_obj(MESHES / mesh_file))
    obj.hapticut.role = "REGION"
    obj.hapticut.material_preset = preset
    obj.data.materials.append(look)
    for polygon in obj.data.polygons:
        polygon.use_smooth = True
    return obj


def knife():
    """A blade: its cutting edge (vertices 0, 1) 40 mm along x, its spine 8 mm above."""
    vertices = [(-20, 0, 0), (20, 0, 0), (-20, -0.5, 8), (20, -0.5, 5), (-20, 0.5, 8),
                (20, 0.5, 5)]  # fmt: skip
    faces = [(0, 1, 3, 2), (1, 0, 4, 5), (2, 3, 5, 4), (1, 5, 3), (0, 2, 4)]
    obj = mesh_object("Knife", vertices, faces)
    obj.hapticut.role = "BLADE"
    obj.hapticut.edge_vertex_a, obj.hapticut.edge_vertex_b = 0, 1
    obj.hapticut.blade_points = 40
    obj.data.materials.append(material("Steel", (0.8, 0.82, 0.85), roughness=0.15))
    return obj


def stroke(obj, seconds: float) -> None:
    """Above the finger; down onto the bone in the first third; across and out."""
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    last = 1 + round(seconds * FPS)
    keys = ((1, (KNIFE_X, 0, 20)), (1 + round(last / 3), (KNIFE_X, 0, -2)),
            (last, (KNIFE_X, 20, -2)))  # fmt: skip
    scene.frame_start, scene.frame_end = 1, last
    for frame, location in keys:
        obj.location = location
        obj.keyframe_insert("location", frame=frame)


def build_scene(work: Path, seconds: float):
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    scene.unit_settings.scale_length = 0.001  # 1 unit = 1 mm.
    scene.hapticut.work_directory = str(work)
    scene.hapticut.accuracy, scene.hapticut.edge_near, scene.hapticut.edge_far = 1.5, 5.0, 20.0
    skin = region("Skin", "finger_skin.obj", "skin", material("Skin", (0.95, 0.7, 0.6), 0.15))
    region("Flesh", "finger_flesh.obj", "soft_tissue", material("Flesh", (0.8, 0.35, 0.35), 0.15))
    bone = material("Bone", (0.95, 0.93, 0.85))
    for part in ("proximal", "middle", "distal"):
        region(f"Bone {part}", f"finger_bone_{part}.obj", "bone", bone)
    # A thin skin: it gives way at 0.5 N a point (the preset's 1.5 N needs a deeper push).
    skin.hapticut.custom_model, skin.hapticut.custom_name = "membrane", "skin"
    with bpy.context.temp_override(object=skin, active_object=skin):
        assert bpy.ops.hapticut.set_custom_material() == {"FINISHED"}
    skin.hapticut.custom_parameters["break_force_N"].value = 0.5
    stroke(knife(), seconds)
    scene.hapticut_live.realtime = False
    scene.hapticut_live.arrow_mm_per_N = 3.0
    return scene


def tetrahedralize(scene) -> float:
    from addon.authoring import building

    began = time.perf_counter()
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    while building.update(scene.name):  # What the timer calls (timers do not run here).
        time.sleep(0.1)
    if scene.hapticut.error:
        sys.exit(f"blender_demo: tetrahedralize failed: {scene.hapticut.error}")
    bpy.data.collections["Hapticut Preview"].hide_render = True
    bpy.data.collections["Hapticut Preview"].hide_viewport = True
    return time.perf_counter() - began


def simulate_and_bake(scene) -> dict:
    from addon import simulate
    from addon.live import live_link

    began = time.perf_counter()
    assert bpy.ops.hapticut.simulate_stroke() == {"FINISHED"}
    # What the timers do in the GUI (they do not run in background mode): the stroke, the bake.
    if bpy.ops.hapticut.wait() != {"FINISHED"} or scene.hapticut_live.error:
        sys.exit(f"blender_demo: the bake failed: {scene.hapticut_live.error}")
    figures = dict(simulate.last_simulate, seconds=time.perf_counter() - began)
    live_link.stop()
    return figures


def stage(scene) -> None:
    """Camera, lights, the bake's looks; the knife object itself hidden in renders (the ideal
    blade shows where the material let it go)."""
    bpy.data.objects["Knife"].hide_render = True
    target = bpy.data.objects.new("Camera target", None)
    scene.collection.objects.link(target)
    target.location = (KNIFE_X + 4, 4, 2)
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.data.lens = 50
    scene.collection.objects.link(camera)
    camera.location = (KNIFE_X + 45, -75, 55)
    constraint = camera.constraints.new("TRACK_TO")
    constraint.target = target
    scene.camera = camera
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 3.0
    sun.rotation_euler = (0.6, 0.3, 0.8)
    scene.collection.objects.link(sun)
    world = bpy.data.worlds.new("World")
    world.color = (0.05, 0.05, 0.06)
    if bpy.app.version < (5, 0, 0):
        world.use_nodes = True
    background = world.node_tree.nodes.get("Background")
    if background is not None:
        background.inputs["Color"].default_value = (0.05, 0.05, 0.06, 1)
        background.inputs["Strength"].default_value = 1.0
    scene.world = world
    cut = bpy.data.materials.get("Hapticut Cut")
    shader = cut.node_tree.nodes.get("Principled BSDF") if cut else None
    if shader is not None:
        shader.inputs["Emission Color"].default_value = (0.9, 0.05, 0.05, 1)
        shader.inputs["Emission Strength"].default_value = 4.0


def render(scene, out: Path, frames: list[int], size=(320, 240), samples=24) -> list[Path]:
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    paths = []
    for frame in frames:
        scene.frame_set(frame)
        path = out / f"frame_{frame:03d}.png"
        scene.render.filepath = str(path)
        bpy.ops.render.render(write_still=True)
        paths.append(path)
    return paths


def contact_sheet(paths: list[Path], target: Path, columns: int = 3) -> None:
    """The frames side by side (left to right, top to bottom) in one PNG."""
    images = []
    for path in paths:
        image = bpy.data.images.load(str(path))
        width, height = image.size
        pixels = np.empty(width * height * 4, np.float32)
        image.pixels.foreach_get(pixels)
        images.append(pixels.reshape(height, width, 4))
    height, width = images[0].shape[:2]
    rows = -(-len(images) // columns)
    gap = 4
    sheet = np.ones((rows * height + (rows - 1) * gap, columns * width + (columns - 1) * gap, 4),
                    np.float32)  # fmt: skip
    for i, pixels in enumerate(images):
        # Blender's pixel rows go bottom to top: the first image belongs in the top row.
        r, c = rows - 1 - i // columns, i % columns
        y, x = r * (height + gap), c * (width + gap)
        sheet[y : y + height, x : x + width] = pixels
    out = bpy.data.images.new("contact sheet", sheet.shape[1], sheet.shape[0], alpha=True)
    out.pixels.foreach_set(sheet.ravel())
    out.filepath_raw = str(target)
    out.file_format = "PNG"
    target.parent.mkdir(parents=True, exist_ok=True)
    out.save()


def stroke_summary(recording_path: str) -> list[str]:
    """The stroke as the servo recorded it: the force on the hand and where the points were."""
    from hapticut import engine
    from hapticut.recording import read_recording

    recording = read_recording(recording_path)
    name = recording.blade_names[0]
    block = recording.blade(name)["block"]
    force = np.linalg.norm(block["force_N"], axis=1)
    peak = int(np.argmax(force))
    states = block["state_counts"].astype(int)  # (T, 5) in engine.STATE_NAMES order
    on_surface = [engine.STATE_NAMES.index(s) for s in ("FACE", "EDGE", "VERTEX")]
    held = states[:, on_surface].sum(axis=1)
    points = int(block["point_count"][0])
    time_s = recording.ticks["time_s"]
    lines = [
        f"stroke: {len(recording)} ticks ({time_s[-1] - time_s[0]:.2f} s at 1 kHz), "
        f"blade {name!r} with {points} points ({recording.coupling(name)}); "
        f"recording {recording_path}",
        f"force on the hand: peak {force[peak]:.2f} N at {time_s[peak] - time_s[0]:.2f} s, "
        f"mean {force.mean():.2f} N; in contact (over 0.1 N) {np.mean(force > 0.1):.0%} "
        "of the ticks",
    ]
    if recording.coupling(name) == "rigid":
        # The whole knife is held: how far its ideal pose stayed from the hand's.
        held_mm = np.linalg.norm(recording.ideal_pose(name)[:, :3] - block["pose"][:, :3], axis=1)
        deepest = int(np.argmax(held_mm))
        lines.append(
            f"the knife held back by the material: up to {held_mm[deepest]:.2f} mm from the "
            f"hand's pose (at {time_s[deepest] - time_s[0]:.2f} s)"
        )
    else:
        counts = ", ".join(
            f"{s} {c}" for s, c in zip(engine.STATE_NAMES, states[peak], strict=True)
        )
        lines.append(
            f"points held on a surface: at most {held.max()} of {points}; "
            f"at the peak force: {counts}"
        )
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=str(REPO / "build" / "blender-demo"))
    parser.add_argument("--sheet", help="the contact sheet's path (default: OUT/contact_sheet.png)")
    parser.add_argument("--stroke-seconds", type=float, default=2.5)
    parser.add_argument("--frames", type=int, default=6, help="how many frames to render")
    parser.add_argument("--samples", type=int, default=24)
    looks = parser.add_mutually_exclusive_group()
    looks.add_argument("--quick", action="store_true", help="render 3 frames at 8 samples")
    looks.add_argument("--no-render", action="store_true", help="build, simulate, bake only")
    args = parser.parse_args()
    if args.quick:
        args.frames, args.samples = 3, 8
    out = Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    stages: list[tuple[str, float]] = []
    began = time.perf_counter()
    enable_addon()
    scene = build_scene(out / "work", args.stroke_seconds)
    stages.append(("scene (add-on, finger, knife, keyed stroke)", time.perf_counter() - began))
    seconds = tetrahedralize(scene)
    stages.append(("tetrahedralize (repair, fTetWild, labels)", seconds))
    print(f"blender_demo: tetrahedralize {seconds:.1f} s", flush=True)
    figures = simulate_and_bake(scene)
    stages.append(("simulate stroke through the servo, bake", figures["seconds"]))
    print(
        f"blender_demo: Simulate stroke to a baked animation {figures['seconds']:.2f} s for a "
        f"{args.stroke_seconds:g} s stroke ({figures['ticks']} ticks at 1 kHz; servo "
        f"{figures['servo_s']:.2f} s, bake {figures.get('bake_s', 0):.2f} s)",
        flush=True,
    )
    began = time.perf_counter()
    stage(scene)
    blend = out / "blender_demo.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend))
    stages.append(("stage and save the .blend", time.perf_counter() - began))
    summary = stroke_summary(scene.hapticut_live.recording_path)
    sheet = None
    if not args.no_render:
        first, last = scene.frame_start, scene.frame_end
        frames = np.linspace(first + (last - first) / 4, last, args.frames)
        began = time.perf_counter()
        paths = render(scene, out / "frames", frames.round().astype(int).tolist(),
                       samples=args.samples)  # fmt: skip
        sheet = Path(args.sheet).resolve() if args.sheet else out / "contact_sheet.png"
        contact_sheet(paths, sheet)
        stages.append((f"render {len(paths)} frames ({args.samples} samples, Cycles on the CPU)",
                       time.perf_counter() - began))  # fmt: skip
    print("\nblender_demo: stages")
    for name, seconds in stages:
        print(f"  {seconds:7.1f} s  {name}")
    print("\n".join(["", *summary, ""]))
    print(f"the .blend: {blend}")
    if sheet is not None:
        print(f"the frames: {out / 'frames'}")
        print(f"the contact sheet: {sheet}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
