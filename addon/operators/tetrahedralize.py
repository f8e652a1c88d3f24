import bpy

from .. import build_job, building


class HAPTICUT_OT_tetrahedralize(bpy.types.Operator):
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

    def invoke(self, context, event):
        result = self.execute(context)
        if "FINISHED" in result and build_job.running(context.scene.name):
            self._scene_name = context.scene.name
            context.window_manager.modal_handler_add(self)
            return {"RUNNING_MODAL"}
        return result

    def modal(self, context, event):
        # Only watches for Esc: the timer follows the build.
        if build_job.running(self._scene_name) is None:
            return {"FINISHED"}
        if event.type == "ESC" and event.value == "PRESS":
            building.cancel_build(self._scene_name)
            self.report({"WARNING"}, "build cancelled")
            return {"CANCELLED"}
        return {"PASS_THROUGH"}
