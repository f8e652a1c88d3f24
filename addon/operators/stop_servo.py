import bpy

from .. import live


class HAPTICUT_OT_stop_servo(bpy.types.Operator):
    """Stop the servo (the force ramps to zero) and the live link"""

    bl_idname = "hapticut.stop_servo"
    bl_label = "Stop"

    @classmethod
    def poll(cls, context):
        return live.current() is not None

    def execute(self, context):
        live.stop()
        return {"FINISHED"}
