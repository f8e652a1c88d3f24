import bpy
from bpy.props import StringProperty

from .. import baking, live, live_session


class HAPTICUT_OT_bake_recording(bpy.types.Operator):
    """Bake the last recording: the ideal blade's keyframes, the force arrow, the cut surface"""

    bl_idname = "hapticut.bake_recording"
    bl_label = "Bake"
    bl_options = {"REGISTER", "UNDO"}

    filepath: StringProperty(
        name="Recording", subtype="FILE_PATH", description="Empty: the scene's last recording"
    )

    def execute(self, context):
        scene = context.scene
        settings = scene.hapticut_live
        path = bpy.path.abspath(self.filepath or settings.recording_path)
        if not path:
            self.report({"ERROR"}, "no recording yet: Simulate Stroke, or Record while live")
            return {"CANCELLED"}
        try:
            link = live.link(context)
            figures = baking.bake(scene, link, path, bpy.path.abspath(settings.preview_path))
        except (baking.BakeError, live_session.SessionError) as error:
            settings.error = str(error)
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        self.report({"INFO"}, f"baked {figures['frames']} frames in {figures['seconds']:.1f} s")
        if figures["truncated"]:
            self.report({"WARNING"}, figures["truncated"])
        return {"FINISHED"}
