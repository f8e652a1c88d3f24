import bpy

from ..authoring import build_job, building
from ..authoring.job_modal import CancelsJobOnEsc


class HAPTICUT_OT_tetrahedralize(CancelsJobOnEsc, bpy.types.Operator):
    """Build the tetrahedral scene from the regions and blades (Esc cancels)"""

    bl_idname = "hapticut.tetrahedralize"
    bl_label = "Tetrahedralize"

    @classmethod
    def poll(cls, context):
        return context.scene is not None and build_job.running(context.scene.name) is None

    def execute(self, context):
        try:
            outcome = building.start_build(context)
        except building.BuildRefusedError as refusal:
            self.report({"ERROR"}, str(refusal))
            return {"CANCELLED"}
        if outcome == "unchanged":
            self.report({"INFO"}, "the scene is unchanged: not rebuilt")
        return {"FINISHED"}
