import os

import bpy

from ..live import live_link


class HAPTICUT_OT_open_servo_log(bpy.types.Operator):
    """Open the servo's log in a text editor block"""

    bl_idname = "hapticut.open_servo_log"
    bl_label = "Servo Log"

    def execute(self, context):
        path = bpy.path.abspath(context.scene.hapticut_live.log_path) or live_link.log_path(
            context.scene
        )
        if not os.path.isfile(path):
            self.report({"ERROR"}, f"no servo log at {path}")
            return {"CANCELLED"}
        text = bpy.data.texts.get("hapticut-servo.log") or bpy.data.texts.new("hapticut-servo.log")
        with open(path, encoding="utf-8", errors="replace") as file:
            text.from_string(file.read())
        self.report({"INFO"}, f"servo log in the text block {text.name!r} ({path})")
        return {"FINISHED"}
