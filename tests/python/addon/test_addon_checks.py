"""Every check names the object and the problem before anything is built."""

import os
import time

import blender_scene
import bpy
import numpy as np
import pytest


def problems() -> list[tuple[str, str]]:
    return [(p.object_name, p.problem) for p in bpy.context.scene.hapticut.problems]


def follow(scene_name: str) -> list[str]:
    """Poll the running check (or build) as the timer does, until it ends; the progress
    texts seen. Prints the longest time one poll took."""
    from addon.authoring import build_job, building

    texts, longest_s = [], 0.0
    deadline = time.monotonic() + 300
    while True:
        job = build_job.running(scene_name)
        began = time.perf_counter()
        still_running = building.update(scene_name)
        longest_s = max(longest_s, time.perf_counter() - began)
        if not still_running:
            break
        texts.append(build_job.progress_text(job))
        assert time.monotonic() < deadline
        time.sleep(0.02)
    print(f"check: longest poll {1000 * longest_s:.1f} ms over {len(texts)} polls")
    return texts


def check(expect_ok: bool = False) -> list[tuple[str, str]]:
    """Check Scene: Blender's own problems fail the operator at once; when they pass, the
    toolkit's check runs as a child (the operator returns while it runs), followed here."""
    from addon.authoring import build_job

    scene = bpy.context.scene
    try:
        result = bpy.ops.hapticut.check_scene()
    except RuntimeError:
        assert not expect_ok, problems()
        return problems()
    assert result == {"FINISHED"}
    assert build_job.running(scene.name).kind == "check"
    follow(scene.name)
    assert bool(problems()) != expect_ok, problems()
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
    from addon.authoring import building

    scene = bpy.context.scene
    scene.hapticut.problems.clear()
    assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
    while building.update(scene.name):
        time.sleep(0.05)
    assert scene.hapticut.error.startswith("Lid: the mesh is open (4 boundary edges), near (")
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

    from addon.authoring import building

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
    from addon.toolkit import runner

    prefs = bpy.context.preferences.addons[blender_scene.ADDON_MODULE].preferences
    toolkit_path = prefs.toolkit_path
    prefs.toolkit_path = str(tmp_path / "nowhere" / "hapticut")
    try:
        with pytest.raises(RuntimeError, match="is not an executable"):
            bpy.ops.hapticut.check_toolkit()
            bpy.ops.hapticut.wait()
        assert runner.INSTALL_COMMAND in prefs.toolkit_error
        assert prefs.toolkit_version == ""
    finally:
        prefs.toolkit_path = toolkit_path
        assert bpy.ops.hapticut.check_toolkit() == {"FINISHED"}
        assert bpy.ops.hapticut.wait() == {"FINISHED"}
    assert prefs.toolkit_version and not prefs.toolkit_error


def test_regions_crossing_are_found_without_tetrahedralizing(addon, tmp_path):
    from addon.authoring import build_job

    scene = blender_scene.empty_scene(str(tmp_path))
    cube("Cow", size=20.0)
    cube("Bone", size=10.0, location=(8.0, 0, 0))  # Half out of the cow.
    blender_scene.knife()
    assert bpy.ops.hapticut.check_scene() == {"FINISHED"}
    job = build_job.running(scene.name)
    assert job.kind == "check" and job.process.poll() is None  # Returned while it runs.
    assert scene.hapticut.running
    texts = follow(scene.name)
    print("check progress:", texts)
    ((name, text),) = problems()
    assert "crosses region" in text and "regions must be nested or apart" in text
    assert {name, text.split("'")[1]} == {"Cow", "Bone"}
    assert scene.hapticut.status == "checked: 1 problem(s)" and not scene.hapticut.running
    assert not os.path.exists(job.job_dir) and sorted(os.listdir(tmp_path)) == []


def test_a_duplicated_region_is_found_naming_both(addon, tmp_path):
    blender_scene.empty_scene(str(tmp_path))
    cow = cube("Cow")
    copy = cow.copy()  # Shift+D: the same mesh in the same place.
    copy.name = "Cow.001"
    bpy.context.scene.collection.objects.link(copy)
    blender_scene.knife()
    ((name, text),) = check()
    other = "Cow.001" if name == "Cow" else "Cow"
    assert name in ("Cow", "Cow.001") and f"region {other!r}" in text, (name, text)


def test_nested_regions_pass_and_say_so(addon, tmp_path):
    scene = blender_scene.empty_scene(str(tmp_path))
    cube("Cow", size=20.0)
    cube("Bone", size=5.0)
    blender_scene.knife()
    assert check(expect_ok=True) == []
    assert scene.hapticut.status == "checked: ready to build"


def test_a_running_check_can_be_cancelled_and_tells_a_slow_one_what_to_do(addon, tmp_path):
    from test_addon_cancel import group_members
    from test_addon_panels import CheckingLayout, draw

    from addon.authoring import build_job
    from addon.ui import scene_panels

    scene = blender_scene.empty_scene(str(tmp_path))
    cube("Cow", size=20.0)
    blender_scene.knife()
    assert bpy.ops.hapticut.check_scene() == {"FINISHED"}
    job = build_job.running(scene.name)
    # Neither a second check nor a build starts beside it.
    with pytest.raises(RuntimeError, match="poll"):
        bpy.ops.hapticut.tetrahedralize()
    # A check running long names what it does and suggests decimating.
    job.started -= build_job.SLOW_CHECK_S + 1
    assert "Decimate modifier" in build_job.progress_text(job)
    layout = CheckingLayout()  # The panel shows the check's progress where it was started.
    draw(scene_panels.HAPTICUT_PT_scene, layout)
    assert any("Decimate modifier" in text for text in layout.texts), layout.texts
    assert bpy.ops.hapticut.cancel_build() == {"FINISHED"}
    assert build_job.running(scene.name) is None
    assert group_members(job.process.pid) == [] and job.process.poll() is not None
    assert not os.path.exists(job.job_dir)
    assert scene.hapticut.status == "check cancelled" and not scene.hapticut.running
    assert sorted(os.listdir(tmp_path)) == []


def test_esc_cancels_a_check_started_from_the_panel(addon, tmp_path):
    # Background mode runs no modal operators: the operator's modal() is called as Blender would.
    import types

    from addon.authoring import build_job
    from addon.authoring.job_modal import CancelsJobOnEsc

    scene = blender_scene.empty_scene(str(tmp_path))
    cube("Cow")
    blender_scene.knife()
    assert bpy.ops.hapticut.check_scene() == {"FINISHED"}
    reports = []
    operator = types.SimpleNamespace(_scene_name=scene.name, report=lambda *a: reports.append(a))
    other_key = types.SimpleNamespace(type="A", value="PRESS")
    assert CancelsJobOnEsc.modal(operator, bpy.context, other_key) == {"PASS_THROUGH"}
    esc = types.SimpleNamespace(type="ESC", value="PRESS")
    assert CancelsJobOnEsc.modal(operator, bpy.context, esc) == {"CANCELLED"}
    assert build_job.running(scene.name) is None and reports == [({"WARNING"}, "check cancelled")]
    assert scene.hapticut.status == "check cancelled"
