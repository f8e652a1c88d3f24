import bpy

from ..live import live_link, live_session


class HAPTICUT_OT_record_live(bpy.types.Operator):
    """Record the live run (again: stop recording); Bake turns the recording into animation"""

    bl_idname = "hapticut.record_live"
    bl_label = "Record"

    def execute(self, context):
        try:
            path = live_link.record_live(context.scene)
        except live_session.LiveServoError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self.report({"INFO"}, f"recording to {path}" if path else "recording stopped")
        return {"FINISHED"}
