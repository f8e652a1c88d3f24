import bpy

from .. import simulate
from ..background import jobs
from ..live import live_session


class HAPTICUT_OT_simulate_stroke(jobs.FollowsJob, bpy.types.Operator):
    """Run the blades' keyframed animation through the servo as fast as possible, recorded,
    then bake it (in the background, Esc cancels)"""

    bl_idname = "hapticut.simulate_stroke"
    bl_label = "Simulate Stroke"

    def execute(self, context):
        try:
            simulate.simulate(context)
        except live_session.LiveServoError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return {"FINISHED"}
