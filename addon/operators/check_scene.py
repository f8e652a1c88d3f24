import bpy

from .. import build_job, building


class HAPTICUT_OT_check_scene(bpy.types.Operator):
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
        self.report({"INFO"}, "checking the meshes: the Build panel shows the progress")
        return {"FINISHED"}

    def invoke(self, context, event):
        result = self.execute(context)
        if "FINISHED" in result and build_job.running(context.scene.name):
            self._scene_name = context.scene.name
            context.window_manager.modal_handler_add(self)
            return {"RUNNING_MODAL"}
        return result

    def modal(self, context, event):
        # Only watches for Esc: the timer follows the check.
        if build_job.running(self._scene_name) is None:
            return {"FINISHED"}
        if event.type == "ESC" and event.value == "PRESS":
            building.cancel_build(self._scene_name)
            self.report({"WARNING"}, "check cancelled")
            return {"CANCELLED"}
        return {"PASS_THROUGH"}
