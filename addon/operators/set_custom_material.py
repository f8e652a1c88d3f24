import bpy

from ..authoring import exchange
from ..toolkit import materials, preferences, runner


class HAPTICUT_OT_set_custom_material(bpy.types.Operator):
    """Give the active region a custom material: the model's parameters at the table's defaults"""

    bl_idname = "hapticut.set_custom_material"
    bl_label = "Custom Material"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.object is not None and context.object.hapticut.role == "REGION"

    def execute(self, context):
        try:
            table = preferences.material_table(context)
        except runner.ToolkitError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        obj = context.object
        if materials.model(table, obj.hapticut.custom_model) is None:
            self.report({"ERROR"}, f"{obj.name}: model {obj.hapticut.custom_model!r} is unknown")
            return {"CANCELLED"}
        obj.hapticut.material_preset = "custom"
        exchange.fill_custom_parameters(obj, table)
        return {"FINISHED"}
