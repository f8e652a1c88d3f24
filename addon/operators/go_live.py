import bpy

from ..background import jobs
from ..live import live_link, live_session


class HAPTICUT_OT_go_live(jobs.FollowsJob, bpy.types.Operator):
    """Run the built scene on the servo with the panel's device (starts the servo if needed;
    the servo starts and loads the scene in the background, Esc cancels)"""

    bl_idname = "hapticut.go_live"
    bl_label = "Go Live"

    def execute(self, context):
        try:
            live_link.go_live(context)
        except live_session.LiveServoError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return {"FINISHED"}
