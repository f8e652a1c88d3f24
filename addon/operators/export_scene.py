import bpy
from bpy.props import StringProperty
from bpy_extras.io_utils import ExportHelper

from ..authoring import building, work_folder
from ..background import jobs
from ..toolkit import preferences, runner


class HAPTICUT_OT_export_scene(bpy.types.Operator, ExportHelper):
    """Write the last built scene as .hapticut.msgpack or .hapticut.json (for the servo)"""

    bl_idname = "hapticut.export_scene"
    bl_label = "Export Scene"

    filename_ext = ".hapticut.msgpack"
    filter_glob: StringProperty(default="*.hapticut.msgpack;*.hapticut.json", options={"HIDDEN"})

    def check(self, context):
        return False  # Keep the user's .json or .msgpack ending.

    def execute(self, context):
        scene = context.scene
        source = building.scene_file(scene)
        if source is None:
            self.report({"ERROR"}, work_folder.no_build_reason(scene))
            return {"CANCELLED"}
        if not self.filepath.endswith((".hapticut.msgpack", ".hapticut.json")):
            self.report(
                {"ERROR"}, f"{self.filepath}: must end in .hapticut.msgpack or .hapticut.json"
            )
            return {"CANCELLED"}
        try:
            executable = preferences.executable(context)
        except runner.ToolkitError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        work = _export_steps(executable, source, self.filepath)
        jobs.start(
            "Export scene", scene.name, work, on_error=jobs.shows_error_in(scene.name, "hapticut")
        )
        return {"FINISHED"}


def _export_steps(executable: str, source: str, path: str):
    yield from runner.quick_steps(executable, "convert", source, path)
    return path
