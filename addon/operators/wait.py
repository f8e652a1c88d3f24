import bpy
from bpy.props import FloatProperty

from .. import waiting
from ..authoring import build_job
from ..background import jobs


class HAPTICUT_OT_wait(bpy.types.Operator):
    """Wait until the scene's build or check and the add-on's job (Go Live, Simulate Stroke
    and its bake, Bake, ...) are over; for scripts: in background mode no timer runs them (in
    the GUI, Blender waits unresponsive)"""

    bl_idname = "hapticut.wait"
    bl_label = "Wait"

    timeout_s: FloatProperty(
        name="Timeout",
        default=3600.0,
        min=0.0,
        description="Seconds before giving up (the work goes on)",
    )
    live_s: FloatProperty(
        name="Run live",
        default=0.0,
        min=0.0,
        description="Then run the live session this many seconds as its timer would (a script "
        "drives a live session headless: move the blade, run, read, again)",
    )

    def execute(self, context):
        scene = context.scene
        was_building = build_job.running(scene.name) is not None
        job = jobs.current()
        try:
            seconds = waiting.wait(scene, self.timeout_s)
        except waiting.WaitTimeoutError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        problem = ""
        if was_building and scene.hapticut.status == "failed":
            problem = f"the build failed: {scene.hapticut.error}"
        elif job is not None and job.state == "failed":
            problem = f"{job.name} failed: {job.error}"
        if problem:
            self.report({"ERROR"}, problem)
            return {"CANCELLED"}
        if self.live_s > 0:
            try:
                waiting.run_live(self.live_s)
            except waiting.NoLiveSessionError as error:
                self.report({"ERROR"}, str(error))
                return {"CANCELLED"}
            seconds += self.live_s
        self.report({"INFO"}, f"done after {seconds:.1f} s")
        return {"FINISHED"}
