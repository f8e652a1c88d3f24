import bpy

from .. import live, live_session


class HAPTICUT_OT_start_servo(bpy.types.Operator):
    """Start the servo (a child process; its output goes to the log the panel links to)"""

    bl_idname = "hapticut.start_servo"
    bl_label = "Start"

    def execute(self, context):
        try:
            live.start(context)
        except live_session.SessionError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return {"FINISHED"}
