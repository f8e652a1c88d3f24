"""The add-on's preferences: where the toolkit is, its version, a Check button."""

from __future__ import annotations

import bpy
from bpy.props import StringProperty

from . import materials, runner

# The add-on's own package (its name differs between an extension and a development folder).
ADDON_ID = __package__.rpartition(".")[0]


class HAPTICUT_AP_preferences(bpy.types.AddonPreferences):
    bl_idname = ADDON_ID

    toolkit_path: StringProperty(
        name="Toolkit",
        description="The hapticut executable (empty: the one on PATH)",
        subtype="FILE_PATH",
    )
    toolkit_version: StringProperty(name="Version")
    toolkit_error: StringProperty(name="Problem")

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "toolkit_path")
        row = layout.row()
        row.operator("hapticut.check_toolkit", icon="FILE_REFRESH")
        if self.toolkit_version:
            row.label(text=f"hapticut {self.toolkit_version}", icon="CHECKMARK")
        if self.toolkit_error:
            layout.label(text=self.toolkit_error, icon="ERROR")
            layout.label(text=f"Install: {runner.INSTALL_COMMAND}")


def preferences(context=None):
    """The add-on's preferences, or None when it was registered without being enabled
    (a development session calling register() itself)."""
    context = context or bpy.context
    addon = context.preferences.addons.get(ADDON_ID)
    return addon.preferences if addon is not None else None


def configured_toolkit_path(context=None) -> str:
    prefs = preferences(context)
    return prefs.toolkit_path if prefs is not None else ""


def executable(context=None) -> str:
    """The toolkit's executable (runner.ToolkitError with the install command if missing)."""
    return runner.find_toolkit(bpy.path.abspath(configured_toolkit_path(context)))


def material_table(context=None, refresh: bool = False) -> dict:
    return materials.material_table(executable(context), refresh=refresh)


classes = (HAPTICUT_AP_preferences,)
