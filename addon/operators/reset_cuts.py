import bpy

from ..live import live_link, live_session


class HAPTICUT_OT_reset_cuts(bpy.types.Operator):
    """Fresh tissue: uncut every tet the blades have cut in the servo's scene (while a run is
    on, from its next tick)"""

    bl_idname = "hapticut.reset_cuts"
    bl_label = "Reset Cuts"

    @classmethod
    def poll(cls, context):
        return live_link.current() is not None

    def execute(self, context):
        try:
            live_link.reset_cuts()
        except live_session.LiveServoError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return {"FINISHED"}
