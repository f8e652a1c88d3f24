import bpy

from ..background import jobs
from ..toolkit import materials, preferences, runner


class HAPTICUT_OT_check_toolkit(jobs.FollowsJob, bpy.types.Operator):
    """Find the hapticut toolkit, show its version and read its material table again"""

    bl_idname = "hapticut.check_toolkit"
    bl_label = "Check"

    def execute(self, context):
        try:
            executable = preferences.executable(context)
        except runner.ToolkitError as error:
            _show_error(str(error))
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        scene = context.scene.name if context.scene else ""
        jobs.start("Check toolkit", scene, _check_steps(executable), on_error=_show_error)
        return {"FINISHED"}

    def summary(self, result):
        return [("INFO", result)]


def _show_error(message: str) -> None:
    materials.forget_material_table()
    prefs = preferences.preferences()
    if prefs is not None:
        prefs.toolkit_version, prefs.toolkit_error = "", message


def _check_steps(executable: str):
    version = yield from runner.version_steps(executable)
    yield from materials.material_table_steps(executable, refresh=True)
    prefs = preferences.preferences()
    if prefs is not None:
        prefs.toolkit_version, prefs.toolkit_error = version, ""
    return f"hapticut {version} at {executable}"
