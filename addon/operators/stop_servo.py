import bpy

from ..background import jobs
from ..live import live_link


class HAPTICUT_OT_stop_servo(jobs.FollowsJob, bpy.types.Operator):
    """Stop the servo (the force ramps to zero) and the live link"""

    bl_idname = "hapticut.stop_servo"
    bl_label = "Stop"

    @classmethod
    def poll(cls, context):
        return live_link.current() is not None

    def execute(self, context):
        # The jobs running and waiting use the servo: they end here.
        jobs.cancel_all()
        live_link.start_job("Stop servo", context.scene.name, live_link.stop_steps())
        return {"FINISHED"}
