"""A first try at the default settings: the Build panel says what each setting costs (before
a build, what 0 derives; after it, the build's own figures), and a keyframed stroke through
the finger with the skin preset at the default stiffness cuts through the skin."""

import json

import blender_scene
import bpy
import live_support
from test_addon_panels import CheckingLayout, draw


def build_panel_texts() -> list[str]:
    from addon.ui import scene_panels

    layout = CheckingLayout()
    draw(scene_panels.HAPTICUT_PT_build, layout)
    return layout.texts


def test_the_panel_says_what_settings_cost_and_the_skin_preset_gives_way(addon, tmp_path):
    from addon.authoring import report_text
    from addon.live import live_link
    from addon.toolkit import materials

    scene = blender_scene.finger_scene(str(tmp_path))
    texts = build_panel_texts()
    assert report_text.FIRST_TRY in texts
    assert all(line in texts for line in report_text.SETTING_COSTS)

    # The skin preset, and the servo's own stiffness (the panel's 0).
    skin = bpy.data.objects["Skin"].hapticut
    assert skin.material_preset == "skin"
    assert scene.hapticut_live.stiffness_N_per_mm == 0.0
    preset = materials.preset(materials.cached_material_table(), "skin")
    scene.hapticut_live.realtime = False
    live_support.build(scene)
    report = json.loads(scene.hapticut.report_json)
    texts = build_panel_texts()
    last = next(t for t in texts if t.startswith("last build: "))
    assert f"{report['tets']:,} tets" in last, last
    assert f"{report['settings']['edge_near_mm']:.2g} / " in last, last

    live_support.keyframe_stroke(bpy.data.objects["Knife"])
    try:
        assert bpy.ops.hapticut.simulate_stroke() == {"FINISHED"}
        assert bpy.ops.hapticut.wait() == {"FINISHED"}
        baked = json.loads(scene.hapticut_live.bake_report)
    finally:
        live_link.stop()
    # The cut surface lies in cuttable material the blade entered: the flesh under the skin.
    cut_faces = baked["blades"]["Knife"]["cut_faces"]
    print(
        f"\nskin preset {preset['parameters']['break_force_N']} N a point at the default "
        f"stiffness: {cut_faces} cut faces"
    )
    assert cut_faces > 0
