"""What the sidebar's panels share: where they are drawn, and rows drawn the same way in
every panel (a column of properties, a status line and an error line)."""

from __future__ import annotations


class SidebarPanel:
    """A panel of the 3D view's sidebar tab *Hapticut* (mixed into each bpy.types.Panel)."""

    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Hapticut"


class SidebarSubpanel(SidebarPanel):
    """A panel under the tab's main panel (ui.HAPTICUT_PT_scene)."""

    bl_parent_id = "HAPTICUT_PT_scene"


def draw_properties(layout, data, names) -> None:
    for name in names:
        layout.prop(data, name)


def draw_status(layout, status: str = "", error: str = "") -> None:
    """The status line (when there is one), then the error line with its icon."""
    if status:
        layout.label(text=status)
    if error:
        layout.label(text=error, icon="ERROR")
