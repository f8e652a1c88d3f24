import bpy

from ..background import jobs


class HAPTICUT_OT_cancel_job(bpy.types.Operator):
    """Stop the running live job (Go Live, Simulate Stroke, Bake...) and the ones waiting
    for it where they are (a servo they started keeps running: Stop ends it)"""

    bl_idname = "hapticut.cancel_job"
    bl_label = "Cancel"

    @classmethod
    def poll(cls, context):
        return jobs.current() is not None

    def execute(self, context):
        job = jobs.current()
        jobs.cancel_all()
        self.report({"WARNING"}, f"{job.name} cancelled")
        return {"FINISHED"}
