import bpy

from ..background import jobs
from ..live import live_link


class HAPTICUT_OT_start_servo(jobs.FollowsJob, bpy.types.Operator):
    """Start the servo (a child process; its output goes to the log the panel links to)"""

    bl_idname = "hapticut.start_servo"
    bl_label = "Start"

    def execute(self, context):
        scene = context.scene
        live_link.start_job("Start servo", scene.name, live_link.start_steps(scene.name))
        return {"FINISHED"}
