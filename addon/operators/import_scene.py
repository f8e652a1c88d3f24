import json
import os
import shutil
import tempfile

import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ImportHelper

from .. import preferences, toolkit
from ..preview import show_preview


class HAPTICUT_OT_import_scene(bpy.types.Operator, ImportHelper):
    """Show a scene file (.hapticut.msgpack or .hapticut.json) as a preview"""

    bl_idname = "hapticut.import_scene"
    bl_label = "Import Scene"
    bl_options = {"REGISTER", "UNDO"}

    filter_glob: StringProperty(default="*.hapticut.msgpack;*.hapticut.json", options={"HIDDEN"})

    def execute(self, context):
        folder = tempfile.mkdtemp(prefix="hapticut-import-")
        preview = os.path.join(folder, "preview.npz")
        try:
            executable = preferences.executable(context)
            toolkit.run_quick(executable, "preview", self.filepath, "--out", preview)
            report = show_preview(context.scene, preview)
        except toolkit.ToolkitError as error:
            self.report({"ERROR"}, str(error))
            context.scene.hapticut.error = str(error)
            return {"CANCELLED"}
        finally:
            shutil.rmtree(folder, ignore_errors=True)
        settings = context.scene.hapticut
        settings.report_json = json.dumps(report)
        settings.status = f"imported {os.path.basename(self.filepath)}"
        settings.error = ""
        return {"FINISHED"}
