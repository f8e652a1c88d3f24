"""Every check names the object and the problem before anything is built."""

import time

import blender_scene
import bpy
import numpy as np
import pytest


def problems() -> list[tuple[str, str]]:
    return [(p.object_name, p.problem) for p in bpy.context.scene.hapticut.problems]


def check(expect_ok: bool = False) -> list[tuple[str, str]]:
    result = bpy.ops.hapticut.check_scene() if expect_ok else None
    if not expect_ok:
        with pytest.raises(RuntimeError):
            bpy.ops.hapticut.check_scene()
    else:
        assert result == {"FINISHED"}
    return problems()


def cube(name, size=10.0, location=(0, 0, 0), drop_faces=0):
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    obj = blender_scene.mesh_object(name, (corners - 0.5) * size, faces[drop_faces:], location)
    obj.hapticut.role = "REGION"
    obj.hapticut.material_preset = "soft_tissue"
    return obj


def test_a_good_scene_passes(addon, tmp_path):
    blender_scene.empty_scene(str(tmp_path))
    cube("Good")
    blender_scene.knife()
    assert check(expect_ok=True) == []


def test_no_region_and_no_blade(addon, tmp_path):
    blender_scene.empty_scene(str(tmp_path))
    found = check()
    assert ("", "no region: mark a closed mesh as a Region") in found
    assert ("", "no blade: mark an object as a Blade") in found
    with pytest.raises(RuntimeError, match="no region"):
        bpy.ops.hapticut.tetrahedralize()


def test_a_blade_without_cutting_edge(addon, tmp_path):
    blender_scene.empty_scene(str(tmp_path))
    cube("Body")
    blade = blender_scene.knife("Scalpel")
    blade.hapticut.edge_vertex_b = -1
    assert check() == [("Scalpel", "the blade has no cutting edge (pick two vertices in edit "
                                   "mode and Set Cutting Edge)")]  # fmt: skip
    blade.hapticut.edge_mode = "AXIS"
    blade.hapticut.edge_length = 0.0
    assert check() == [("Scalpel", "the blade has no cutting edge (its length is 0)")]
    blade.hapticut.edge_length = 30.0
    assert check(expect_ok=True) == []


def test_an_open_mesh(addon, tmp_path):
    blender_scene.empty_scene(str(tmp_path))
    cube("Lid", drop_faces=1)
    blender_scene.knife()
    assert ("Lid", "the mesh is open (4 boundary edges)") in check()
    # Tetrahedralize: the child checks first, fails, and its error reaches the panel.
    from addon import building

    scene = bpy.context.scene
    scene.hapticut.problems.clear()
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    while building.update(scene.name):
        time.sleep(0.05)
    assert scene.hapticut.error == "Lid: the mesh is open (4 boundary edges)"
    assert problems() == [("Lid", "the mesh is open (4 boundary edges)")]
    assert scene.hapticut.status == "failed"
    assert not (tmp_path / "build").exists()


def test_a_self_intersecting_mesh(addon, tmp_path):
    blender_scene.empty_scene(str(tmp_path))
    a = cube("Twins")
    # Join a second, overlapping cube into the same mesh: closed, but crossing itself.
    other = np.array([v.co[:] for v in a.data.vertices]) + 3.0
    faces = [tuple(v + 8 for v in p.vertices) for p in a.data.polygons]
    vertices = [v.co[:] for v in a.data.vertices] + [tuple(v) for v in other]
    mesh = bpy.data.meshes.new("Twins")
    mesh.from_pydata(vertices, [], [tuple(p.vertices) for p in a.data.polygons] + faces)
    a.data = mesh
    blender_scene.knife()
    found = check()
    assert any(name == "Twins" and "intersects itself" in text for name, text in found), found


def test_a_region_without_volume(addon, tmp_path):
    blender_scene.empty_scene(str(tmp_path))
    flat = cube("Flat")
    flat.scale = (1.0, 1.0, 0.0)  # Closed, but flattened to nothing by its transform.
    blender_scene.knife()
    found = check()
    assert any(name == "Flat" and "no volume" in text for name, text in found), found


def test_a_modifier_stack_that_cannot_be_evaluated(addon, tmp_path):
    blender_scene.empty_scene(str(tmp_path))
    body = cube("Noded")
    modifier = body.modifiers.new("Empty nodes", "NODES")
    modifier.node_group = bpy.data.node_groups.new("Nothing", "GeometryNodeTree")
    blender_scene.knife()
    found = check()
    assert found == [("Noded", "its modifier stack cannot be evaluated: it leaves no faces")]


def test_a_failing_child_shows_its_last_error_line(addon, tmp_path):
    # A real executable that is not the toolkit: Python itself fails on "build-request".
    import sys

    from addon import building

    scene = blender_scene.empty_scene(str(tmp_path))
    cube("Body")
    blender_scene.knife()
    prefs = bpy.context.preferences.addons[blender_scene.ADDON_MODULE].preferences
    toolkit_path = prefs.toolkit_path
    prefs.toolkit_path = sys.executable
    try:
        assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
        while building.update(scene.name):
            time.sleep(0.05)
    finally:
        prefs.toolkit_path = toolkit_path
    assert scene.hapticut.status == "failed"
    assert scene.hapticut.error.startswith("the build failed (exit 2): ")
    assert "can't open file" in scene.hapticut.error and "build-request" in scene.hapticut.error


def test_a_missing_toolkit_names_the_install_command(addon, tmp_path):
    from addon import toolkit

    prefs = bpy.context.preferences.addons[blender_scene.ADDON_MODULE].preferences
    toolkit_path = prefs.toolkit_path
    prefs.toolkit_path = str(tmp_path / "nowhere" / "hapticut")
    try:
        with pytest.raises(RuntimeError, match="is not an executable"):
            bpy.ops.hapticut.check_toolkit()
        assert toolkit.INSTALL_COMMAND in prefs.toolkit_error
        assert prefs.toolkit_version == ""
    finally:
        prefs.toolkit_path = toolkit_path
        assert bpy.ops.hapticut.check_toolkit() == {"FINISHED"}
    assert prefs.toolkit_version and not prefs.toolkit_error
