import bpy

from .. import live, live_session


class HAPTICUT_OT_simulate_stroke(bpy.types.Operator):
    """Run the blades' keyframed animation through the servo as fast as possible, recorded,
    then bake it"""

    bl_idname = "hapticut.simulate_stroke"
    bl_label = "Simulate Stroke"

    def execute(self, context):
        try:
            live.simulate(context)
        except live_session.SessionError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return {"FINISHED"}
