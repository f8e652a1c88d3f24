import bpy

from ..bake import baking


class HAPTICUT_OT_clear_bake(bpy.types.Operator):
    """Remove everything the last bake made"""

    bl_idname = "hapticut.clear_bake"
    bl_label = "Clear"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        removed = baking.clear(context.scene)
        self.report({"INFO"}, f"removed {removed} baked objects")
        return {"FINISHED"}
