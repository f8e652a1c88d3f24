import bpy
from bpy.props import StringProperty

from ..authoring import recording_stamp
from ..authoring.properties import BLEND_RELATIVE
from ..background import jobs, undo_steps
from ..bake import baking
from ..live import live_link, live_session
from ..toolkit import preferences, toolkit_link


class HAPTICUT_OT_bake_recording(jobs.FollowsJob, bpy.types.Operator):
    """Bake the last recording: the ideal blade's keyframes, the force arrow, the cut surface
    (in the background, Esc cancels)"""

    bl_idname = "hapticut.bake_recording"
    bl_label = "Bake"
    # No UNDO: the bake changes the scene later, from the job, which pushes its own step.
    bl_options = {"REGISTER"}

    filepath: StringProperty(
        name="Recording",
        subtype="FILE_PATH",
        options=BLEND_RELATIVE,
        description="Empty: the scene's last recording",
    )

    def execute(self, context):
        scene = context.scene
        settings = scene.hapticut_live
        path = bpy.path.abspath(self.filepath or settings.recording_path)
        if not path:
            self.report({"ERROR"}, "no recording yet: Simulate Stroke, or Record while live")
            return {"CANCELLED"}
        try:  # The build on disk that is the scene's now: never an older one an undo named.
            _, preview = live_link.built_scene(scene)
        except live_session.LiveServoError as error:
            self.report({"ERROR"}, f"cannot bake: {error}")
            return {"CANCELLED"}
        refusal = recording_stamp.refusal(scene, path, chosen=bool(self.filepath))
        if refusal:
            self.report({"ERROR"}, f"cannot bake: {refusal}")
            return {"CANCELLED"}
        shown = jobs.shows_error_in(scene.name, "hapticut_live")
        jobs.start("Bake", scene.name, _bake_steps(scene.name, path, preview), on_error=shown)
        return {"FINISHED"}

    def summary(self, figures):
        done = [("INFO", f"baked {figures['frames']} frames in {figures['seconds']:.1f} s")]
        return done + ([("WARNING", figures["truncated"])] if figures["truncated"] else [])


def _bake_steps(scene_name: str, path: str, preview: str):
    link = yield from toolkit_link.link_steps(preferences.executable())
    figures = yield from baking.bake_steps(scene_name, link, path, preview)
    undo_steps.push("Bake")
    return figures
