import bpy

from .. import checking


class HAPTICUT_OT_check_scene(bpy.types.Operator):
    """Check the regions and blades (closed, not self-intersecting, with volume, a cutting edge)"""

    bl_idname = "hapticut.check_scene"
    bl_label = "Check Scene"

    def execute(self, context):
        problems = checking.check_scene(context, with_toolkit=True)
        if problems:
            first = problems[0]
            self.report({"ERROR"}, f"{len(problems)} problem(s); first: {first}")
            return {"CANCELLED"}
        self.report({"INFO"}, "the scene is ready to build")
        return {"FINISHED"}
