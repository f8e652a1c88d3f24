import bpy

from ..background import jobs
from ..live import live_link


class HAPTICUT_OT_refresh_devices(jobs.FollowsJob, bpy.types.Operator):
    """List the devices the servo can drive (hapticut-servo --list-devices --json): the HID
    devices connected, with the profile each matches, the shipped profiles, sim, viewport and
    the UDP bridge, each with its limits (the stiffness limit at the panel's rate)"""

    bl_idname = "hapticut.refresh_devices"
    bl_label = "Refresh Devices"

    def execute(self, context):
        scene = context.scene
        # Its error goes to the device line of the panel (device_error).
        work = live_link.refresh_devices_steps(scene.name)
        live_link.start_job("Refresh devices", scene.name, work, show_error=False)
        return {"FINISHED"}

    def summary(self, listing):
        found = sum(1 for d in listing["devices"] if d.get("profile"))
        return [("INFO", f"{len(listing['devices'])} HID devices, {found} with a profile")]
