import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ExportHelper

from .. import building, preferences, toolkit


class HAPTICUT_OT_export_scene(bpy.types.Operator, ExportHelper):
    """Write the last built scene as .hapticut.msgpack or .hapticut.json (for the servo)"""

    bl_idname = "hapticut.export_scene"
    bl_label = "Export Scene"

    filename_ext = ".hapticut.msgpack"
    filter_glob: StringProperty(default="*.hapticut.msgpack;*.hapticut.json", options={"HIDDEN"})

    def check(self, context):
        return False  # Keep the user's .json or .msgpack ending.

    def execute(self, context):
        source = building.scene_file(context.scene)
        if source is None:
            self.report({"ERROR"}, "no scene built yet: Tetrahedralize first")
            return {"CANCELLED"}
        if not self.filepath.endswith((".hapticut.msgpack", ".hapticut.json")):
            self.report(
                {"ERROR"}, f"{self.filepath}: must end in .hapticut.msgpack or .hapticut.json"
            )
            return {"CANCELLED"}
        try:
            toolkit.run_quick(preferences.executable(context), "convert", source, self.filepath)
        except toolkit.ToolkitError as error:
            self.report({"ERROR"}, str(error))
            context.scene.hapticut.error = str(error)
            return {"CANCELLED"}
        self.report({"INFO"}, f"scene written to {self.filepath}")
        return {"FINISHED"}
