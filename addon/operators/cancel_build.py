import bpy

from ..authoring import build_job, building


class HAPTICUT_OT_cancel_build(bpy.types.Operator):
    """Stop the running build or check (nothing it made is kept)"""

    bl_idname = "hapticut.cancel_build"
    bl_label = "Cancel Build"

    @classmethod
    def poll(cls, context):
        return context.scene is not None and build_job.running(context.scene.name) is not None

    def execute(self, context):
        job = build_job.running(context.scene.name)
        building.cancel_build(context.scene.name)
        self.report({"WARNING"}, f"{job.kind} cancelled")
        return {"FINISHED"}
