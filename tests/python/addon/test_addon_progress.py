"""The progress bar says what the toolkit does: its step, and which meshing when it meshes
again, from the real toolkit's progress lines."""

import blender_scene
import bmesh
import bpy
from test_addon_checks import follow


def icosphere(name: str, radius_mm: float):
    mesh = bpy.data.meshes.new(name)
    shape = bmesh.new()
    bmesh.ops.create_icosphere(shape, subdivisions=2, radius=radius_mm)
    shape.to_mesh(mesh)
    shape.free()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.hapticut.role = "REGION"
    obj.hapticut.material_preset = "soft_tissue"
    return obj


def test_a_build_that_meshes_again_shows_which_meshing(addon, tmp_path):
    # The real toolkit with its envelope three times the accuracy (as test_scene_build.py
    # patches it): fTetWild's surface strays beyond the accuracy and the build meshes again.
    patch = tmp_path / "patch"
    patch.mkdir()
    (patch / "sitecustomize.py").write_text(
        "from hapticut.scenebuild import builder\nbuilder.ENVELOPE_SHARE = 3.0\n"
    )
    prefs = bpy.context.preferences.addons[blender_scene.ADDON_MODULE].preferences
    toolkit_path = prefs.toolkit_path
    wrapper = tmp_path / "hapticut"
    wrapper.write_text(
        f'#!/bin/sh\nPYTHONPATH="{patch}${{PYTHONPATH:+:$PYTHONPATH}}" exec "{toolkit_path}" "$@"\n'
    )
    wrapper.chmod(0o755)
    scene = blender_scene.empty_scene(str(tmp_path / "work"))
    scene.hapticut.accuracy = 0.3
    icosphere("Ball", 10.0)
    blender_scene.knife()
    prefs.toolkit_path = str(wrapper)
    try:
        assert bpy.ops.hapticut.tetrahedralize() == {"FINISHED"}
        texts = follow(scene.name)
    finally:
        prefs.toolkit_path = toolkit_path
    assert scene.hapticut.status.startswith("built in "), scene.hapticut.error
    again = [text for text in texts if ", meshing again, " in text]
    for text in dict.fromkeys(again):
        print(text)
    assert again, texts
    assert any(text.startswith("tetrahedralize, meshing again, 2 of 3 ") for text in again)
    assert not any(text.startswith("report") and "fTetWild" in text for text in texts)
