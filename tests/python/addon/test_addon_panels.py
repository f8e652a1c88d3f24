"""The panels' draw code against the real properties and operators (background mode draws
nothing, so a layout that checks each call stands in for Blender's), and Set Cutting Edge."""

import json
import types

import blender_scene
import bpy
import pytest


class CheckingLayout:
    """Records what a panel draws; fails on a property or operator that does not exist."""

    def __init__(self) -> None:
        self.texts: list[str] = []
        self.operators: list[str] = []
        self.props: list[str] = []

    def prop(self, data, name, **options):
        assert name in data.bl_rna.properties, f"{type(data).__name__} has no {name!r}"
        self.props.append(name)

    def operator(self, idname, **options):
        module, name = idname.split(".")
        assert hasattr(getattr(bpy.ops, module), name), idname
        getattr(getattr(bpy.ops, module), name).get_rna_type()  # Raises when unregistered.
        self.operators.append(idname)
        return types.SimpleNamespace()  # Its properties, set by the panel.

    def label(self, text="", **options):
        self.texts.append(text)

    def progress(self, factor=0.0, type="BAR", text=""):
        assert 0.0 <= factor <= 1.0
        self.texts.append(text)

    def template_list(self, list_type, list_id, data, propname, active_data, active_propname):
        assert hasattr(bpy.types, list_type)
        assert (
            propname in data.bl_rna.properties and active_propname in active_data.bl_rna.properties
        )

    def row(self, **options):
        return self

    def column(self, **options):
        return self


def draw(panel_class, layout) -> None:
    panel = types.SimpleNamespace(layout=layout)
    if hasattr(panel_class, "draw_region"):
        panel.draw_region = lambda *args: panel_class.draw_region(panel, *args)
    panel_class.draw(panel, bpy.context)


def test_every_panel_draws_for_each_role_and_state(addon, tmp_path):
    import addon as extension  # noqa: F401 - the add-on's package, registered by the fixture
    from addon.ui import scene_panels

    scene = blender_scene.finger_scene(str(tmp_path))
    settings = scene.hapticut
    settings.report_json = json.dumps({"tets": 10, "boundary_faces": 4, "timings_s": {"total": 1}})
    for obj_name, preset in (("Skin", None), ("Flesh", "custom"), ("Knife", None)):
        obj = bpy.data.objects[obj_name]
        if preset:
            obj.hapticut.material_preset = preset
        bpy.context.view_layer.objects.active = obj
        for running in (False, True):
            settings.running, settings.progress, settings.stage = running, 0.4, "label"
            drawn = {}
            for panel_class in (
                scene_panels.HAPTICUT_PT_scene,
                scene_panels.HAPTICUT_PT_object,
                scene_panels.HAPTICUT_PT_build,
                scene_panels.HAPTICUT_PT_report,
            ):
                drawn[panel_class] = CheckingLayout()
                draw(panel_class, drawn[panel_class])
            assert ("label 40%" in drawn[scene_panels.HAPTICUT_PT_build].texts) == running
    settings.running = False
    layout = CheckingLayout()
    draw(scene_panels.HAPTICUT_PT_report, layout)
    assert layout.texts[0] == "10 tets, 4 boundary faces"
    prefs = bpy.context.preferences.addons[blender_scene.ADDON_MODULE].preferences
    prefs.toolkit_error = "missing"
    layout = CheckingLayout()
    type(prefs).draw(types.SimpleNamespace(layout=layout, bl_rna=prefs.bl_rna, **{
        name: getattr(prefs, name) for name in ("toolkit_path", "toolkit_version", "toolkit_error")
    }), bpy.context)  # fmt: skip
    assert any(text.startswith("Install: ") for text in layout.texts)
    prefs.toolkit_error = ""


def test_once_cut_is_offered_for_materials_a_blade_cuts(addon, tmp_path):
    from addon.ui import scene_panels

    blender_scene.finger_scene(str(tmp_path))
    drawn = {}
    for name, becomes in (("Flesh", "WEAKER"), ("Skin", "FREE"), ("Bone", "WEAKER")):
        obj = bpy.data.objects[name]
        obj.hapticut.cut_becomes, obj.hapticut.cut_factor = becomes, 0.25
        bpy.context.view_layer.objects.active = obj
        drawn[name] = CheckingLayout()
        draw(scene_panels.HAPTICUT_PT_object, drawn[name])
    assert {"cut_becomes", "cut_factor"} <= set(drawn["Flesh"].props)
    assert "once cut: drag: drag_distance_mm 0.5" in drawn["Flesh"].texts  # 2 mm x 0.25.
    assert "cut_becomes" in drawn["Skin"].props and "cut_factor" not in drawn["Skin"].props
    assert not {"cut_becomes", "cut_factor"} & set(drawn["Bone"].props)
    assert "Once cut: a blade never cuts rigid material" in drawn["Bone"].texts


def test_problems_and_warnings_show_their_place_and_remedy_and_a_shared_folder_its_fork(
    addon, data_home, tmp_path
):
    from addon.authoring import work_folder, work_owner
    from addon.ui import scene_panels

    scene = blender_scene.finger_scene("")
    settings = scene.hapticut
    problem = settings.problems.add()
    problem.object_name, problem.problem = "Skin", "the mesh is open (4 boundary edges)"
    problem.place, problem.remedy = "near (1, 2, 3) in Skin's own units", "close the holes"
    layout = CheckingLayout()
    draw(scene_panels.HAPTICUT_PT_scene, layout)
    shown = " ".join(layout.texts)
    assert "Skin: the mesh is open" in shown and "near (1, 2, 3) in Skin's own units" in shown
    assert "To fix: close the holes" in shown
    settings.report_json = json.dumps(
        {
            "tets": 10,
            "settings": {"edge_near_mm": 2.0},
            "accuracy_not_held": [
                {"region": "Skin", "deviation_mm": 1.43, "accuracy_mm": 1.21, "lost_mm": 1.43,
                 "strayed_mm": 0.2, "lost_features": []}
            ],
        }
    )  # fmt: skip
    layout = CheckingLayout()
    draw(scene_panels.HAPTICUT_PT_build, layout)
    shown = " ".join(layout.texts)
    assert "accuracy not held: Skin lies up to 1.43 mm" in shown
    assert "To fix: lower Edge near (now 2 mm)" in shown
    assert "hapticut.fork_work_folder" not in layout.operators
    # The folder owned by another file on disk: the panel offers the fork.
    other = tmp_path / "other.blend"
    other.write_bytes(b"")
    work_owner.claim(work_folder.work_directory(scene), str(other))
    layout = CheckingLayout()
    draw(scene_panels.HAPTICUT_PT_build, layout)
    assert "hapticut.fork_work_folder" in layout.operators


def test_set_cutting_edge_takes_the_two_selected_vertices(addon, tmp_path):
    blender_scene.finger_scene(str(tmp_path))
    knife = bpy.data.objects["Knife"]
    for vertex in knife.data.vertices:
        vertex.select = vertex.index in (1, 2)
    with bpy.context.temp_override(object=knife, active_object=knife):
        assert bpy.ops.hapticut.set_cutting_edge() == {"FINISHED"}
    assert (knife.hapticut.edge_vertex_a, knife.hapticut.edge_vertex_b) == (1, 2)
    knife.data.vertices[0].select = True
    with (
        bpy.context.temp_override(object=knife, active_object=knife),
        pytest.raises(RuntimeError, match="Knife: select exactly two vertices"),
    ):
        bpy.ops.hapticut.set_cutting_edge()
