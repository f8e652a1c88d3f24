import bpy

from .. import preferences, toolkit


class HAPTICUT_OT_check_toolkit(bpy.types.Operator):
    """Find the hapticut toolkit, show its version and read its material table again"""

    bl_idname = "hapticut.check_toolkit"
    bl_label = "Check"

    def execute(self, context):
        prefs = preferences.preferences(context)
        try:
            executable = preferences.executable(context)
            version = toolkit.toolkit_version(executable)
            toolkit.material_table(executable, refresh=True)
        except toolkit.ToolkitError as error:
            toolkit.forget_material_table()
            if prefs is not None:
                prefs.toolkit_version, prefs.toolkit_error = "", str(error)
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        if prefs is not None:
            prefs.toolkit_version, prefs.toolkit_error = version, ""
        self.report({"INFO"}, f"hapticut {version} at {executable}")
        return {"FINISHED"}
