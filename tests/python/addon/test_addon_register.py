"""Registering and unregistering the add-on, twice, leaves Blender as it was."""

import sys

import blender_scene
import bpy


def _registered() -> dict:
    return {
        "scene": hasattr(bpy.types.Scene, "hapticut"),
        "object": hasattr(bpy.types.Object, "hapticut"),
        "operator": hasattr(bpy.types, "HAPTICUT_OT_tetrahedralize"),
        "panel": hasattr(bpy.types, "HAPTICUT_PT_scene"),
    }


def test_register_and_unregister_twice():
    if str(blender_scene.REPO) not in sys.path:
        sys.path.insert(0, str(blender_scene.REPO))
    import addon

    was_enabled = hasattr(bpy.types.Scene, "hapticut")
    if was_enabled:
        addon.unregister()
    assert not any(_registered().values())
    for _ in range(2):
        addon.register()
        assert all(_registered().values())
        # The operators are callable once registered.
        assert bpy.ops.hapticut.tetrahedralize.poll()
        addon.unregister()
        assert not any(_registered().values())
    if was_enabled:
        addon.register()


def test_classes_register_in_order_and_unregister_in_reverse():
    import addon

    names = [cls.__name__ for cls in addon.classes]
    # Property groups before what points at them, panels after their parents.
    assert names.index("HAPTICUT_PG_parameter") < names.index("HAPTICUT_PG_object")
    assert names.index("HAPTICUT_PT_scene") < names.index("HAPTICUT_PT_build")
    assert len(set(names)) == len(names)


def test_enable_and_disable_as_an_addon(addon):
    # Fresh preferences: registering again (above) replaced the fixture's.
    prefs = blender_scene.enable_addon()
    assert prefs.toolkit_version  # The Check button found the toolkit.
    assert not prefs.toolkit_error
    blender_scene.disable_addon()
    assert not hasattr(bpy.types.Scene, "hapticut")
    blender_scene.enable_addon()
    assert hasattr(bpy.types.Scene, "hapticut")
