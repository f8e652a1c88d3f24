"""Simulate stroke and bake, with the real servo: a keyframed knife through the finger's skin
and flesh onto its bone; the ideal blade's keyframes follow the recording; the cut surface lies
in cuttable material only (checked against the scene's tets by the engine); Clear; the bake
survives a save and reopen and renders."""

import json
import time

import bpy
import cut_outline
import live_support
import mathutils
import numpy as np
import pytest

CUTTABLE = {"drag", "viscous", "membrane"}
# A baked edge resting on the bone touches it: Blender keeps keyframes in single precision,
# which rounds a pose some 20 mm from the origin by about 1e-6 mm (and a rotation's rounding
# swings the edge's ends as much again), so a sample this deep is still on the surface.
ON_BONE_MM = 1e-4


@pytest.fixture(scope="module")
def baked(addon, tmp_path_factory):
    from addon import simulate
    from addon.bake import baking
    from addon.live import live_link

    scene = live_support.finger_with_stroke(tmp_path_factory.mktemp("live-finger"))
    began = time.perf_counter()
    assert bpy.ops.hapticut.simulate_stroke() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    seconds = time.perf_counter() - began
    figures = simulate.last_simulate
    print(
        f"\nSimulate stroke to a baked animation ({figures['ticks']} ticks, "
        f"{scene.frame_end - scene.frame_start} frames): {seconds:.2f} s (servo "
        f"{figures['servo_s']:.2f} s, bake {figures.get('bake_s', 0):.2f} s)"
    )
    assert scene.hapticut_live.error == ""
    assert baking.baked_objects()
    yield scene
    live_link.stop()


def recording(scene):
    from addon.live import live_link

    return live_link.link().read_recording(scene.hapticut_live.recording_path)


def test_the_stroke_ran_every_tick_and_the_bake_made_its_objects(baked):
    rec = recording(baked)
    duration_s = (baked.frame_end - baked.frame_start) / 24
    # Every tick of the stroke, then the stop ramp (0.1 s) after it.
    assert duration_s * 1000 <= len(rec) <= duration_s * 1000 + 110
    assert rec.ticks["dropped_records"][-1] == 0
    assert rec.header["as_fast_as_possible"] is True
    # The servo closed it cleanly: the trailer is there, and the bake says nothing of a cut.
    assert not rec.truncated and rec.dropped_records == 0
    assert json.loads(baked.hapticut_live.bake_report)["truncated"] == ""
    names = {o.name for o in bpy.data.collections["Hapticut Bake"].objects}
    assert names == {"Ideal Knife", "Force Knife", "Cut Knife"}


def test_the_ideal_blade_keyframes_follow_the_recording(baked):
    from addon.bake import baking
    from addon.live import live_link

    rec = recording(baked)
    blade = rec.blade("Knife")
    times = rec.elapsed_s()
    frames, nearest = live_link.link().frame_ticks(times, 24.0, baked.frame_start)
    ideal = bpy.data.objects["Ideal Knife"]
    knife = bpy.data.objects["Knife"]
    assert len(frames) >= baked.frame_end - baked.frame_start + 1
    placed = baking.ideal_poses(rec, "Knife", nearest)
    for frame, k, (location, rotation) in zip(frames, nearest, placed, strict=True):
        if (frame - frames[0]) % 5:
            continue
        baked.frame_set(int(frame))
        assert np.allclose(ideal.matrix_world.translation, location, atol=1e-4)
        assert abs(ideal.matrix_world.to_quaternion().rotation_difference(rotation).angle) < 1e-4
        # The device followed the keyframed knife (no simulated hand), to within the nearest
        # tick (0.5 ms at under 50 mm/s).
        assert np.allclose(blade["block"]["pose"][k][:3], knife.matrix_world.translation, atol=0.03)
    # Deepest (frame 18): the knife is 3 mm under the bone's axis, the ideal blade held up
    # by the bone (most of its points on the bone's surface, 3.5 mm above the axis).
    baked.frame_set(18)
    assert knife.matrix_world.translation.z == pytest.approx(live_support.DEEPEST_Z)
    assert ideal.matrix_world.translation.z > knife.matrix_world.translation.z + 2.0
    # The force arrow pushes the knife back up, out of the bone.
    arrow = bpy.data.objects["Force Knife"]
    up = arrow.matrix_world.to_quaternion() @ mathutils.Vector((0, 0, 1))
    assert up.z > 0.8 and arrow.matrix_world.to_scale().z > 1.0


def test_no_negative_frame_age_is_shown_after_simulate(baked):
    """A stroke runs as fast as possible: its servo time is virtual (ahead of the clock), so
    its frames have no age to show."""
    from addon.live import live_link, live_session
    from addon.ui import live_panels

    session = live_link.current()
    assert session.stream_frame is not None  # The stroke's last frame is kept.
    lines = [line for line in live_panels.status_lines(session) if line.startswith("frame age")]
    print(f"\nafter Simulate stroke: {lines or 'no frame age line'}")
    assert all(age >= 0 for age in session.stream_frame_ages_s + session.drawn_ages_s)
    assert not any("-" in line.partition(":")[2] for line in lines), lines
    assert live_session.stream_frame_age_s(session.stream_frame, time.monotonic()) is None


def baked_curves():
    from addon.live import stroke_path

    for name in ("Ideal Knife", "Force Knife"):
        curves = stroke_path.object_fcurves(bpy.data.objects[name])
        assert curves, name
        yield from ((name, curve) for curve in curves)


def test_every_baked_key_is_linear(baked):
    for name, curve in baked_curves():
        kinds = {key.interpolation for key in curve.keyframe_points}
        assert kinds == {"LINEAR"}, (name, curve.data_path, kinds)


def test_the_keys_stay_in_the_frame_range_and_the_panel_says_what_is_not_baked(baked):
    from addon.ui import live_panels

    first, last = baked.frame_start, baked.frame_end
    for name, curve in baked_curves():
        frames = [key.co.x for key in curve.keyframe_points]
        assert first <= min(frames) and max(frames) <= last, (name, min(frames), max(frames))
        assert len(frames) == last - first + 1, (name, curve.data_path, len(frames))
    # The stroke's stop ramp runs after the last frame: not baked, and the panel says so.
    report = json.loads(baked.hapticut_live.bake_report)
    lines = live_panels.bake_lines(report)
    print(f"\n{lines}")
    assert report["frame_range"] == [first, last] and report["unbaked_frames"] > 0
    assert any(line.endswith("not baked") for line in lines)


def test_the_force_arrow_is_scaled_to_the_scene(baked):
    """Automatic (Arrow length 0, the default): the peak force's arrow spans
    ARROW_SCENE_FRACTION of the scene's diagonal, whatever the scene's size."""
    from addon.bake import baking
    from addon.live import live_link
    from addon.toolkit.units import mm_per_unit

    mm = mm_per_unit(baked)
    corners = np.array(
        [
            obj.matrix_world @ mathutils.Vector(corner)
            for obj in (bpy.data.objects[name] for name in ("Skin", "Flesh", "Bone"))
            for corner in obj.bound_box
        ]
    )
    diagonal_mm = float(np.linalg.norm(corners.max(axis=0) - corners.min(axis=0))) * mm
    arrow = bpy.data.objects["Force Knife"]
    lengths_mm = []
    for frame in range(baked.frame_start, baked.frame_end + 1):
        baked.frame_set(frame)
        lengths_mm.append(arrow.matrix_world.to_scale().z * mm)
    report = json.loads(baked.hapticut_live.bake_report)
    print(
        f"\nforce arrow: longest {max(lengths_mm):.1f} mm on a scene of {diagonal_mm:.1f} mm "
        f"diagonal ({report.get('arrow_mm_per_N', baked.hapticut_live.arrow_mm_per_N):.2f} "
        f"mm/N, peak {report['blades']['Knife']['max_force_N']:.2f} N)"
    )
    assert 0.1 * diagonal_mm < max(lengths_mm) <= 0.25 * diagonal_mm
    assert baked.hapticut_live.arrow_mm_per_N == 0.0
    assert max(lengths_mm) == pytest.approx(
        baking.ARROW_SCENE_FRACTION
        * baking.scene_diagonal_mm(
            baking.load_preview_tets(live_link.link(), baked.hapticut_live.preview_path)
        ),
        rel=0.05,
    )


def test_the_preview_is_left_out_of_renders(baked):
    preview = bpy.data.collections["Hapticut Preview"]
    assert preview.objects and preview.hide_render


def test_the_baked_knife_rests_on_the_bone_and_never_enters_it(baked):
    """The default blade is rigid: the servo's ideal pose places the whole knife, and its
    cutting edge, sampled at ten times the blade's point density, is never in bone."""
    from addon.authoring import building
    from addon.toolkit.units import mm_per_unit

    rec = recording(baked)
    assert rec.coupling("Knife") == "rigid"
    ideal = bpy.data.objects["Ideal Knife"]
    knife = bpy.data.objects["Knife"]
    edge = [knife.data.vertices[i].co.copy() for i in (0, 1)]
    samples_per_frame = 10 * knife.hapticut.blade_points
    mm = mm_per_unit(baked)
    samples, lowest = [], []
    for frame in range(baked.frame_start, baked.frame_end + 1):
        baked.frame_set(frame)
        a, b = (ideal.matrix_world @ v for v in edge)
        line = [a.lerp(b, t) for t in np.linspace(0.0, 1.0, samples_per_frame)]
        samples.extend([list(v * mm) for v in line])
        lowest.append(min(v.z for v in line) * mm)
    depths = live_support.bone_depths(building.scene_file(baked), samples)
    print(f"\ndeepest baked edge sample in bone: {max(depths):.3g} mm")
    inside = [(samples[i], d) for i, d in enumerate(depths) if d > ON_BONE_MM]
    assert inside == [], f"{len(inside)} of {len(samples)} edge samples in bone: {inside[:3]}"
    # Held up by the bone: at the deepest keyed frame the device is 3 mm under the bone's
    # axis, the baked edge above the bone's top (its radius is about 3.5 mm).
    baked.frame_set(18)
    assert knife.matrix_world.translation.z * mm == pytest.approx(live_support.DEEPEST_Z)
    assert lowest[18 - baked.frame_start] > 0.0


def test_the_cut_surface_is_in_cuttable_material_only_and_opens_over_time(baked):
    from addon.authoring import building

    cut = bpy.data.objects["Cut Knife"]
    mesh = cut.data
    assert len(mesh.polygons) > 50
    # The swept surface lies halfway between the slit's two sheets (test_cut_slit.py).
    sheets = np.array([v.co for v in mesh.vertices])
    vertices = (sheets[: len(sheets) // 2] + sheets[len(sheets) // 2 :]) / 2
    front = np.array([p.vertices[:] for p in mesh.polygons])[: len(mesh.polygons) // 2]
    corners = vertices[front]
    centres = corners.mean(axis=1)
    midpoints = (corners + np.roll(corners, 1, axis=1)).reshape(-1, 3) / 2
    samples = np.vstack([centres, midpoints, vertices])
    models = live_support.probe_materials(building.scene_file(baked), samples, cut=True)
    assert set(models) <= CUTTABLE, sorted(set(models) - CUTTABLE)
    # Through the flesh (a pierced skin lets the proxies through within a few ticks).
    assert "drag" in set(models)
    # Each face carries its frame; the modifier shows only the faces cut so far.
    data = mesh.attributes["hapticut_cut_frame"].data
    frames = np.zeros(len(data), np.int32)
    data.foreach_get("value", frames)
    assert frames.min() >= baked.frame_start and frames.max() <= baked.frame_end
    shown = []
    for frame in (baked.frame_start, int(np.median(frames)), baked.frame_end):
        baked.frame_set(frame)
        evaluated = cut.evaluated_get(bpy.context.evaluated_depsgraph_get())
        shown.append(len(evaluated.data.polygons))
    assert shown[0] == 0 < shown[1] < shown[2] == len(mesh.polygons)


def test_the_cut_is_a_slit_on_either_side_of_the_blade(baked):
    """Two sheets, slit_mm off the swept surface each side (the blade's plane), facing away
    from each other: the blade's faces never share their depth."""
    mesh = bpy.data.objects["Cut Knife"].data
    slit_mm = json.loads(baked.hapticut_live.bake_report)["blades"]["Knife"]["cut_slit_mm"]
    assert 0.0 < slit_mm < 1.0  # The test knife is flat: the scene's share alone.
    sheets = np.array([v.co for v in mesh.vertices])
    front, back = sheets[: len(sheets) // 2], sheets[len(sheets) // 2 :]
    gaps = np.linalg.norm(front - back, axis=1) * blender_scene_mm(baked)
    # A face of no area (rows of the swept surface where the blade stood still, held by the
    # bone's friction) has no normal to part along: the slit leaves it, and it shows nothing.
    corners = front.reshape(-1, 3, 3)
    areas = np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    assert (areas > 0).sum() > 50
    with_area = np.repeat(areas > 0, 3)
    assert np.median(gaps[with_area]) == pytest.approx(2 * slit_mm, rel=1e-3)
    normals = np.array([p.normal for p in mesh.polygons])
    half = len(normals) // 2
    facing = np.einsum("ij,ij->i", normals[:half], normals[half:])[areas > 0]
    print(f"\ncut slit {slit_mm:.3f} mm on {half} faces")
    assert facing.max() < 0  # Back to back.


def test_the_cut_outline_follows_the_edge_path_not_the_tets(baked):
    """The baked cut's outline lies on the outline of the edge's swept path within the
    cuttable material (cut_outline.py): the deviation of its outline vertices is a small
    fraction of the tets' size (a cut of whole tets or quads steps by up to a tet)."""
    from addon.bake import baking
    from addon.live import live_link
    from addon.toolkit.units import mm_per_unit

    link = live_link.link()
    rec = recording(baked)
    _, nearest = link.frame_ticks(rec.elapsed_s(), 24.0, baked.frame_start, baked.frame_end)
    ticks = int(nearest[-1]) + 1
    blade = rec.blade("Knife")
    q, states = blade["q"][:ticks], blade["state"][:ticks]
    tets = baking.load_preview_tets(link, baked.hapticut_live.preview_path)
    module = link.modules["cut_surface"]
    locator = module.TetLocator(tets["vertices"], tets["tets"])

    def cuttable(points):
        in_tet = np.zeros(len(points), np.uint8)
        return module.cuttable_points(points, in_tet, locator, tets["materials"], tets["models"])

    mesh = bpy.data.objects["Cut Knife"].data
    sheets = np.array([v.co for v in mesh.vertices]) * mm_per_unit(baked)
    vertices = (sheets[: len(sheets) // 2] + sheets[len(sheets) // 2 :]) / 2
    faces = np.array([p.vertices[:] for p in mesh.polygons])[: len(mesh.polygons) // 2]
    rows = cut_outline.path_rows(q)
    deviation = cut_outline.outline_deviation(
        vertices, faces, q[rows], cut_outline.allowed_quads(states, rows), cuttable
    )
    # The tets' size: the median edge of the tets the surface's faces lie in.
    held = np.unique(locator.locate(vertices[faces].mean(axis=1)))
    corners = np.asarray(tets["vertices"])[np.asarray(tets["tets"])[held[held >= 0]]]
    pairs = ([0, 0, 0, 1, 1, 2], [1, 2, 3, 2, 3, 3])
    tet_mm = float(np.median(np.linalg.norm(corners[:, pairs[0]] - corners[:, pairs[1]], axis=-1)))
    worst, most, middle = (float(np.percentile(deviation, p)) for p in (100, 90, 50))
    print(
        f"\ncut outline: {len(deviation)} vertices, off the edge's swept path by at most "
        f"{worst:.3f} mm, 90 % within {most:.3f} mm, median {middle:.3f} mm "
        f"(tets {tet_mm:.2f} mm)"
    )
    # Whole quads kept by their corners left most outline vertices up to about a tet's edge
    # inside (the 90th percentile near the whole edge). Where the edge's chord dips into the
    # bone for less than the sampling step, the outline is on the bone: the probes round the
    # vertex find it (cut_outline.boundary_distance). The worst is printed, and at most one
    # vertex in a hundred may stray past a fifth of a tet's edge.
    strays = int(np.count_nonzero(deviation > 0.2 * tet_mm))
    assert strays <= 0.01 * len(deviation), f"{strays} of {len(deviation)} vertices stray"
    assert most < 0.05 * tet_mm and middle < 0.02 * tet_mm


def blender_scene_mm(scene) -> float:
    return 1000.0 * scene.unit_settings.scale_length


def test_clear_removes_the_bake_and_bake_remakes_it_from_the_recording(baked):
    from addon.bake import baking

    assert bpy.ops.hapticut.clear_bake() == {"FINISHED"}
    assert not baking.baked_objects()
    assert "Hapticut Bake" not in bpy.data.collections
    assert "Hapticut Cut Reveal" not in bpy.data.node_groups
    assert bpy.data.objects["Knife"].data.name in bpy.data.meshes  # The blade's mesh stays.
    assert bpy.ops.hapticut.bake_recording() == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert len(baking.baked_objects()) == 3


def test_a_truncated_recording_bakes_its_whole_records_and_says_so(baked, tmp_path):
    from addon.live import live_link

    complete = recording(baked)
    original = baked.hapticut_live.recording_path
    data = open(original, "rb").read()  # noqa: SIM115
    keep = len(complete) // 2
    records_start = 16 + int.from_bytes(data[8:16], "little")  # After the magic and header.
    cut = tmp_path / "cut.rec"
    cut.write_bytes(data[: records_start + keep * complete.records.itemsize])
    assert bpy.ops.hapticut.bake_recording(filepath=str(cut)) == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    report = json.loads(baked.hapticut_live.bake_report)
    problem = live_link.link().read_recording(cut).problem
    assert report["ticks"] == keep and report["truncated"] == problem
    assert problem.startswith(f"recording {str(cut)!r} is truncated") and f"{keep} whole" in problem
    assert bpy.ops.hapticut.bake_recording(filepath=original) == {"FINISHED"}
    assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert json.loads(baked.hapticut_live.bake_report)["truncated"] == ""


def test_the_bake_survives_save_and_reopen_and_renders(baked, tmp_path):
    path = str(tmp_path / "baked.blend")
    faces = len(bpy.data.objects["Cut Knife"].data.polygons)
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.read_homefile(use_empty=True)
    bpy.ops.wm.open_mainfile(filepath=path)
    scene = bpy.context.scene
    assert len(bpy.data.objects["Cut Knife"].data.polygons) == faces
    assert bpy.data.objects["Cut Knife"].modifiers["Hapticut Reveal"].node_group is not None
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    camera.location = (0, -60, 30)
    camera.rotation_euler = (1.1, 0, 0)
    scene.camera = camera
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 1
    scene.render.resolution_x, scene.render.resolution_y = 48, 32
    scene.render.filepath = str(tmp_path / "frame.png")
    scene.frame_set(40)
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(str(tmp_path / "frame.png"))
    assert tuple(image.size) == (48, 32)
