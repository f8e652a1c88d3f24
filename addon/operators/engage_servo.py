import bpy
from bpy.props import BoolProperty

from ..live import live_link, live_session


class HAPTICUT_OT_engage_servo(bpy.types.Operator):
    """Engage (force on, ramped) or disengage the device"""

    bl_idname = "hapticut.engage_servo"
    bl_label = "Engage"

    engaged: BoolProperty(name="Engaged", default=True)

    @classmethod
    def poll(cls, context):
        return live_link.current() is not None

    def execute(self, context):
        try:
            live_link.engage(self.engaged)
        except live_session.LiveServoError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return {"FINISHED"}
