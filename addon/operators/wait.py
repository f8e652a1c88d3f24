import bpy
from bpy.props import FloatProperty

from .. import build_job, live, waiting


class HAPTICUT_OT_wait(bpy.types.Operator):
    """Wait until the scene's build and a running Simulate Stroke (and its bake) are over; for
    scripts: in background mode no timer follows them (in the GUI, Blender waits unresponsive)"""

    bl_idname = "hapticut.wait"
    bl_label = "Wait"

    timeout_s: FloatProperty(
        name="Timeout",
        default=3600.0,
        min=0.0,
        description="Seconds before giving up (the build or stroke goes on)",
    )

    def execute(self, context):
        scene = context.scene
        was_building = build_job.running(scene.name) is not None
        was_simulating = waiting.simulating()
        live_error_before = scene.hapticut_live.error
        try:
            seconds = waiting.wait(scene, self.timeout_s)
        except waiting.WaitTimeoutError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        problem = ""
        if was_building and scene.hapticut.status == "failed":
            problem = f"the build failed: {scene.hapticut.error}"
        elif was_simulating:
            live_error = scene.hapticut_live.error
            error = live.last_error() or (live_error if live_error != live_error_before else "")
            problem = f"the stroke failed: {error}" if error else ""
        if problem:
            self.report({"ERROR"}, problem)
            return {"CANCELLED"}
        self.report({"INFO"}, f"done after {seconds:.1f} s")
        return {"FINISHED"}
