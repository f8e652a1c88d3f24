import bpy

from .. import live, live_session


class HAPTICUT_OT_refresh_devices(bpy.types.Operator):
    """List the devices the servo can drive (hapticut-servo --list-devices --json): the HID
    devices connected, with the profile each matches, the shipped profiles, sim, viewport and
    the UDP bridge, each with its limits (the stiffness limit at the panel's rate)"""

    bl_idname = "hapticut.refresh_devices"
    bl_label = "Refresh Devices"

    def execute(self, context):
        try:
            listing = live.refresh_devices(context)
        except live_session.SessionError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        found = sum(1 for d in listing["devices"] if d.get("profile"))
        self.report({"INFO"}, f"{len(listing['devices'])} HID devices, {found} with a profile")
        return {"FINISHED"}
