import bpy

from ..authoring import build_job, building
from ..authoring.job_modal import CancelsJobOnEsc


class HAPTICUT_OT_check_scene(CancelsJobOnEsc, bpy.types.Operator):
    """Check the regions and blades (closed, not self-intersecting, with volume, a cutting edge;
    regions nested or apart), as Tetrahedralize checks them, without meshing (Esc cancels)"""

    bl_idname = "hapticut.check_scene"
    bl_label = "Check Scene"

    @classmethod
    def poll(cls, context):
        return context.scene is not None and build_job.running(context.scene.name) is None

    def execute(self, context):
        try:
            problems = building.start_check(context)
        except building.BuildRefusedError as refusal:
            self.report({"ERROR"}, str(refusal))
            return {"CANCELLED"}
        if problems:
            first = problems[0]
            self.report({"ERROR"}, f"{len(problems)} problem(s); first: {first}")
            return {"CANCELLED"}
        self.report({"INFO"}, "checking the meshes (the panel shows the progress; Esc cancels)")
        return {"FINISHED"}
