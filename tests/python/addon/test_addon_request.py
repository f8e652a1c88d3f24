"""What the add-on writes for the builder: evaluated meshes in mm, world transforms applied,
materials from the toolkit's table, blades in their tool frame."""

import json

import blender_scene
import bpy
import numpy as np
import pytest


def written_request(tmp_path):
    from addon.authoring import exchange
    from addon.toolkit import preferences

    depsgraph = bpy.context.evaluated_depsgraph_get()
    path, digest = exchange.write_request(
        bpy.context.scene, depsgraph, preferences.material_table(), str(tmp_path / "request")
    )
    with open(path) as file:
        request = json.load(file)
    meshes = {r["name"]: np.load(tmp_path / "request" / r["mesh"]) for r in request["regions"]}
    return request, meshes, digest


def test_metres_in_blender_are_mm_for_the_toolkit(addon, tmp_path):
    # The finger modelled in metres (1 unit = 1 m), moved and with a modifier.
    scene = blender_scene.finger_scene(str(tmp_path), scale=0.001)
    scene.unit_settings.scale_length = 1.0
    skin = bpy.data.objects["Skin"]
    skin.location = (0.01, 0.0, 0.0)  # 10 mm
    skin.scale = (2.0, 1.0, 1.0)
    bpy.data.objects["Bone"].modifiers.new("Subdivide", "SUBSURF").levels = 1
    bpy.data.objects["Knife"].scale = (0.5, 1.0, 1.0)
    request, meshes, _ = written_request(tmp_path)
    vertices = meshes["Skin"]["vertices"]
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    assert low[0] == pytest.approx(2 * -40 + 10, abs=1e-3)
    assert high[0] == pytest.approx(2 * 40 + 10, abs=1e-3)
    assert high[1] == pytest.approx(9.0, abs=0.1)
    # The modifier applied: a subdivided bone has 4x the faces (triangles) of the input.
    source_faces = len(bpy.data.objects["Bone"].data.polygons)
    assert len(meshes["Bone"]["faces"]) > 3 * source_faces
    assert request["settings"]["accuracy_mm"] == pytest.approx(blender_scene.TEST_ACCURACY_MM)
    (blade,) = request["blades"]
    assert blade["start_mm"] == pytest.approx([-10.0, 0, 0])  # 40 mm long, scaled by 0.5.
    assert blade["end_mm"] == pytest.approx([10.0, 0, 0])
    assert blade["points"] == 20
    assert (blade["coupling"], blade["orientation"]) == ("rigid", "free")  # The defaults.


def test_materials_come_from_the_toolkit_table(addon, tmp_path):
    from addon.toolkit import materials, preferences

    table = preferences.material_table()
    blender_scene.finger_scene(str(tmp_path))
    request, _, _ = written_request(tmp_path)
    written = {r["name"]: r["material"] for r in request["regions"]}
    for name, preset in (("Skin", "skin"), ("Flesh", "soft_tissue"), ("Bone", "bone")):
        entry = materials.preset(table, preset)
        assert written[name] == {"name": preset, "model": entry["model"], **entry["parameters"]}
    # The shipped presets, with their models.
    models = {p["name"]: p["model"] for p in table["presets"]}
    assert models == {"air": "free", "soft_tissue": "drag", "fat": "viscous",
                      "skin": "membrane", "bone": "rigid"}  # fmt: skip


def test_a_custom_material_takes_the_table_defaults_and_ranges(addon, tmp_path):
    from addon.authoring import exchange
    from addon.toolkit import materials, preferences

    table = preferences.material_table()
    blender_scene.finger_scene(str(tmp_path))
    flesh = bpy.data.objects["Flesh"]
    flesh.hapticut.custom_model = "drag"
    with bpy.context.temp_override(object=flesh, active_object=flesh):
        assert bpy.ops.hapticut.set_custom_material() == {"FINISHED"}
    (parameter,) = materials.model(table, "drag")["parameters"]
    item = flesh.hapticut.custom_parameters[parameter["name"]]
    assert item.value == pytest.approx(parameter["default"])
    request, _, digest = written_request(tmp_path)
    material = next(r["material"] for r in request["regions"] if r["name"] == "Flesh")
    assert material == {"name": "Flesh", "model": "drag", parameter["name"]: parameter["default"]}
    item.value = parameter["maximum"] * 2
    with pytest.raises(exchange.SceneProblemError, match=f"Flesh: {parameter['name']}"):
        written_request(tmp_path)
    item.value = parameter["default"] * 0.5
    assert written_request(tmp_path)[2] != digest  # An edit changes the build's digest.


def test_once_cut_goes_into_the_request_for_materials_a_blade_cuts(addon, tmp_path):
    from addon.authoring import exchange

    blender_scene.finger_scene(str(tmp_path))
    flesh, skin, bone = (bpy.data.objects[name].hapticut for name in ("Flesh", "Skin", "Bone"))
    request, _, digest = written_request(tmp_path)
    assert not any("cut" in r["material"] for r in request["regions"])  # Stays as it is.
    flesh.cut_becomes, flesh.cut_factor = "WEAKER", 0.25
    skin.cut_becomes = "FREE"
    bone.cut_becomes = "WEAKER"  # Rigid: a blade never cuts it, so it has no effect.
    request, _, weaker_digest = written_request(tmp_path)
    cuts = {r["name"]: r["material"].get("cut") for r in request["regions"]}
    assert cuts == {"Flesh": {"becomes": "weaker", "factor": 0.25},
                    "Skin": {"becomes": "free"}, "Bone": None}  # fmt: skip
    assert weaker_digest != digest
    flesh.cut_factor = 0.5
    assert written_request(tmp_path)[2] != weaker_digest
    flesh.cut_factor = 0.0
    with pytest.raises(exchange.SceneProblemError, match="Flesh: Once cut: Factor 0 .*Free"):
        written_request(tmp_path)
