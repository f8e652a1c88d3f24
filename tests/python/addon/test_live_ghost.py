"""The knife drawn at its ideal pose in the live view: the blade object's edges moved by the
transform that takes the object's own pose to the frame's ideal pose (``stream_frame_geometry``'s
``knife``, LINES pairs), with no servo and no GPU."""

import types

import bpy
import mathutils
import numpy as np
import pytest


def knife_object(scene):
    """A small knife mesh, rotated, scaled unevenly and off the origin."""
    mesh = bpy.data.meshes.new("Ghost Knife")
    vertices = [(-2.0, 0, 0), (2.0, 0, 0), (2.0, 0, 0.5), (-2.0, 0, 0.5), (0, 0.3, 0.25)]
    edges = [(0, 1), (1, 2), (2, 3), (3, 0), (0, 4), (2, 4)]
    mesh.from_pydata(vertices, edges, [])
    obj = bpy.data.objects.new("Ghost Knife", mesh)
    scene.collection.objects.link(obj)
    obj.location = (3.0, -1.0, 2.5)
    obj.rotation_euler = (0.3, -0.5, 1.1)
    obj.scale = (1.5, 0.5, 2.0)
    bpy.context.view_layer.update()
    return obj


def frame_with(name: str, ideal_pose) -> types.SimpleNamespace:
    """A frame of one blade (the fields stream_frame_geometry reads) with this ideal pose."""
    points = np.zeros((2, 3))
    block = {"engine_force_N": np.zeros(3), "ideal_pose": np.asarray(ideal_pose, np.float64)}
    return types.SimpleNamespace(blades={name: {"q": points, "p": points, "block": block}})


def pose_mm(matrix: mathutils.Matrix, mm: float) -> list[float]:
    location, rotation, _ = matrix.decompose()
    return [*(location * mm), *rotation.normalized()]


def edge_points(obj, transform: mathutils.Matrix) -> np.ndarray:
    """The object's edges (LINES pairs) in the world, moved by transform (a world matrix)."""
    mesh = obj.data
    return np.array(
        [transform @ obj.matrix_world @ mesh.vertices[i].co for e in mesh.edges for i in e.vertices]
    )


@pytest.fixture()
def scene_in_cm(addon):
    """1 Blender unit = 10 mm, so the mm of the poses and the units differ."""
    scene = bpy.context.scene
    saved = scene.unit_settings.scale_length
    scene.unit_settings.scale_length = 0.01
    yield scene
    scene.unit_settings.scale_length = saved
    for obj in [o for o in bpy.data.objects if o.name.startswith("Ghost Knife")]:
        bpy.data.objects.remove(obj)


def test_the_ghost_is_the_object_moved_by_the_ideal_pose_transform(scene_in_cm):
    from addon.live import live_draw
    from addon.toolkit.units import mm_per_unit

    mm = mm_per_unit(scene_in_cm)
    knife = knife_object(scene_in_cm)
    # The ideal pose: the object's pose turned 20 degrees about a tilted axis through the
    # world's origin, then moved (Blender units).
    turn = mathutils.Quaternion(mathutils.Vector((0.2, 1.0, -0.4)).normalized(), 0.35)
    transform = mathutils.Matrix.Translation((0.8, -0.3, 1.2)) @ turn.to_matrix().to_4x4()
    own = mathutils.Matrix.LocRotScale(*knife.matrix_world.decompose()[:2], None)
    ideal = pose_mm(transform @ own, mm)
    geometry = live_draw.stream_frame_geometry(
        frame_with(knife.name, ideal), mm, scene_in_cm.objects
    )
    expected = edge_points(knife, transform)
    assert geometry["knife"].shape == (2 * len(knife.data.edges), 3)
    error = np.abs(geometry["knife"] - expected).max()
    print(f"\nghost vertices vs the object moved by the known transform: {error:.2e} units")
    assert error < 1e-5


def test_the_ghost_coincides_with_the_object_at_its_own_pose(scene_in_cm):
    from addon.live import live_draw, stroke_path
    from addon.toolkit.units import mm_per_unit

    mm = mm_per_unit(scene_in_cm)
    knife = knife_object(scene_in_cm)
    ideal = stroke_path.pose_of(knife.matrix_world, mm)  # What a viewport device sends.
    geometry = live_draw.stream_frame_geometry(
        frame_with(knife.name, ideal), mm, scene_in_cm.objects
    )
    expected = edge_points(knife, mathutils.Matrix.Identity(4))
    assert np.abs(geometry["knife"] - expected).max() < 1e-5


def test_the_edges_are_read_once_per_mesh(scene_in_cm):
    from addon.live import live_draw

    knife = knife_object(scene_in_cm)
    edges = live_draw.object_edges(knife)
    assert live_draw.object_edges(knife) is edges  # A new frame reads nothing of the mesh.
    knife.data.vertices.add(1)
    knife.data.edges.add(1)
    knife.data.edges[-1].vertices = (0, 5)
    assert len(live_draw.object_edges(knife)) == len(edges) + 2


def test_a_blade_without_a_mesh_object_draws_no_ghost(scene_in_cm):
    from addon.live import live_draw

    geometry = live_draw.stream_frame_geometry(
        frame_with("No Such Blade", [0, 0, 0, 1, 0, 0, 0]), 10.0, scene_in_cm.objects
    )
    assert geometry["knife"].shape == (0, 3)
    assert (
        live_draw.stream_frame_geometry(frame_with("No Such Blade", [0] * 7), 10.0)["knife"].size
        == 0
    )
