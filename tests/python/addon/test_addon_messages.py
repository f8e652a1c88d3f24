"""Every check and build message names the place (the object, a point in its own units and
the world's, the faces) and the remedy (docs/addon.md, "Checks"); closed parts of one object
that touch are caught; the build report's warnings reach the Build panel with their remedy."""

import re
import time

import blender_scene
import bpy
import numpy as np
import pytest
from mathutils import Matrix, Vector

CUBE_FACES = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
PLACE = re.compile(
    r"near \(([^)]*)\) in (\w+)'s own units, \(([^)]*)\) mm in the world; faces ([\d, ]+)"
)


def cubes(name: str, offsets, size=10.0, location=(0.0, 0.0, 0.0), scale=1.0):
    """One region object made of a cube of size at each offset (its own units)."""
    corners = (np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)]) - 0.5) * size
    vertices, faces = [], []
    for offset in offsets:
        faces += [tuple(v + len(vertices) for v in face) for face in CUBE_FACES]
        vertices += [tuple(c + np.array(offset)) for c in corners]
    obj = blender_scene.mesh_object(name, vertices, faces, location)
    obj.scale = (scale, scale, scale)
    obj.hapticut.role = "REGION"
    obj.hapticut.material_preset = "soft_tissue"
    return obj


def placed(text: str, obj) -> tuple[Vector, list[int]]:
    """The point (object's own units) and faces a message names, after checking that its
    world point is that point through the object's transform, in mm."""
    found = PLACE.search(text)
    assert found, text
    local = Vector([float(c) for c in found.group(1).split(",")])
    world = Vector([float(c) for c in found.group(3).split(",")])
    assert found.group(2) == obj.name
    mm = 1000.0 * bpy.context.scene.unit_settings.scale_length
    expected = (Matrix(obj.matrix_world) @ local) * mm
    assert (world - expected).length <= 0.01 * max(1.0, expected.length), (world, expected)
    faces = [int(f) for f in found.group(4).replace(" ", "").split(",") if f]
    assert all(0 <= f < len(obj.data.polygons) for f in faces)
    return local, faces


def follow_check(scene) -> None:
    from addon.authoring import building

    deadline = time.monotonic() + 300
    while building.update(scene.name):
        assert time.monotonic() < deadline
        time.sleep(0.05)


def problem_items(scene) -> list:
    return list(scene.hapticut.problems)


def test_a_self_intersecting_mesh_says_where_and_how_to_fix(addon, tmp_path):
    scene = blender_scene.empty_scene(str(tmp_path))
    twins = cubes("Twins", [(0, 0, 0), (3, 3, 3)], location=(100.0, 0.0, 0.0), scale=2.0)
    blender_scene.knife()
    assert bpy.ops.hapticut.check_scene() == {"FINISHED"}  # Blender's own checks pass.
    follow_check(scene)
    (item,) = [p for p in problem_items(scene) if "intersects itself" in p.problem]
    local, faces = placed(item.place, twins)
    # The crossing lies where the two cubes overlap, (-2..5) in each axis, on their faces.
    assert all(-5.0 <= c <= 8.0 for c in local), local
    assert any(f < 6 for f in faces) and any(f >= 6 for f in faces), faces
    assert "bpy.ops.object.voxel_remesh()" in item.remedy
    assert "Voxel Remesh" in item.remedy


def test_an_open_mesh_says_where_the_hole_is(addon, tmp_path):
    from addon.authoring import building

    scene = blender_scene.empty_scene(str(tmp_path))
    lid = cubes("Lid", [(0, 0, 0)], location=(0.0, 0.0, 40.0))
    faces = [tuple(p.vertices) for p in lid.data.polygons][1:]  # The x = -5 face gone.
    vertices = [v.co[:] for v in lid.data.vertices]
    lid.data = bpy.data.meshes.new("Lid")
    lid.data.from_pydata(vertices, [], faces)
    blender_scene.knife()
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    while building.update(scene.name):
        time.sleep(0.05)
    assert scene.hapticut.status == "failed"
    error = scene.hapticut.error
    assert error.startswith("Lid: the mesh is open (4 boundary edges), near (")
    local, _ = placed(error, lid)
    assert local.x == pytest.approx(-5.0, abs=0.6), local  # The rim of the missing face.
    assert "Select All by Trait > Non Manifold" in error and "bpy.ops.mesh.fill()" in error


# Each contact: the second cube's offset, and the coordinates fixed on the contact (x = 5 on
# the shared face, x = y = 5 on the shared edge, all three at the shared corner).
@pytest.mark.parametrize(
    ("contact", "offset", "on_contact"),
    [
        ("an edge", (10.0, 10.0, 0.0), (0, 1)),
        ("a face", (10.0, 0.0, 0.0), (0,)),
        ("a corner", (10.0, 10.0, 10.0), (0, 1, 2)),
    ],
)
def test_closed_parts_of_one_object_that_touch_are_caught(
    addon, tmp_path, contact, offset, on_contact
):
    scene = blender_scene.empty_scene(str(tmp_path))
    pair = cubes("Pair", [(0, 0, 0), offset], location=(0.0, 0.0, -30.0))
    blender_scene.knife()
    with pytest.raises(RuntimeError, match="Pair: closed parts touch, near") as refused:
        bpy.ops.hapticut.check_scene()
    assert "Mesh > Separate > By Loose Parts" in str(refused.value), contact
    (item,) = problem_items(scene)
    local, faces = placed(item.place, pair)
    assert all(local[axis] == pytest.approx(5.0, abs=0.01) for axis in on_contact), local
    assert any(f < 6 for f in faces) and any(f >= 6 for f in faces), faces
    with pytest.raises(RuntimeError, match="closed parts touch"):
        bpy.ops.hapticut.tetrahedralize()


def test_closed_parts_apart_pass_blenders_check(addon, tmp_path):
    from addon.authoring import build_job, checking

    scene = blender_scene.empty_scene(str(tmp_path))
    cubes("Pair", [(0, 0, 0), (10.5, 0.0, 0.0)])
    blender_scene.knife()
    assert bpy.ops.hapticut.check_scene() == {"FINISHED"}
    assert build_job.running(scene.name) is not None
    follow_check(scene)
    assert all(p.problem != checking.TOUCHING for p in problem_items(scene))


def test_crossing_regions_say_where_they_cross(addon, tmp_path):
    scene = blender_scene.empty_scene(str(tmp_path))
    cow = cubes("Cow", [(0, 0, 0)], size=20.0)
    cubes("Bone", [(0, 0, 0)], location=(8.0, 0.0, 0.0))  # Half out of the cow.
    blender_scene.knife()
    assert bpy.ops.hapticut.check_scene() == {"FINISHED"}
    follow_check(scene)
    (item,) = [p for p in problem_items(scene) if "crosses region" in p.problem]
    obj = bpy.data.objects[item.object_name]
    local, _ = placed(item.place, obj)
    if obj == cow:  # The cow's x = 10 side, where the bone comes out.
        assert local.x == pytest.approx(10.0, abs=1.0), local
    assert "nested or apart" in item.remedy and "Boolean" in item.remedy


def test_the_reports_warnings_carry_their_remedy():
    """The report's accuracy miss and the toolkit's units warning, as the Build panel shows
    them (report_text.warnings, no bpy)."""
    from addon.authoring.report_text import warnings

    report = {
        "settings": {"edge_near_mm": 1.5, "accuracy_mm": 1.21},
        "warnings": ["region 'Cow' is 0.1 mm across: mesh files have no units, is it in mm?"],
        "accuracy_not_held": [
            {
                "region": "Cow",
                "deviation_mm": 1.2134,
                "accuracy_mm": 1.21,
                "lost_mm": 1.2134,
                "strayed_mm": 0.4,
                "lost_features": [
                    {"kind": "thin part", "thickness_mm": 0.22, "centre_mm": [-8, -40, 26]}
                ],
            }
        ],
    }
    (units, units_fix), (miss, miss_fix) = warnings(report)
    assert "Unit Scale" in units_fix
    assert "up to 1.213 mm" in miss and "beyond the accuracy (1.21 mm)" in miss
    assert "lost a thin part 0.22 mm across near (-8, -40, 26) mm" in miss
    assert "lower Edge near (now 1.5 mm)" in miss_fix and "raise Accuracy to 1.3 mm" in miss_fix
    report["accuracy_not_held"][0]["strayed_mm"] = 2.0
    assert warnings(report)[1][1].startswith("lower Accuracy")
