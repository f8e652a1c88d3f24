"""What the sidebar's panels share: where they are drawn, and rows drawn the same way in
every panel (a column of properties, a status line and an error line)."""

from __future__ import annotations

import textwrap

# About one character of the interface's font in pixels, at a UI scale of 1.
CHARACTER_PX = 7.0


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


def wrapped(context, text: str) -> list[str]:
    """text in lines that fit the sidebar's width (a label does not wrap by itself)."""
    region = getattr(context, "region", None)
    # Without a window (background mode) the scale reads 0.
    scale = (context.preferences.system.ui_scale if context.preferences else 0.0) or 1.0
    width = region.width if region is not None else 300
    return textwrap.wrap(text, max(24, int(width / (CHARACTER_PX * scale)))) or [""]


def draw_wrapped(layout, context, text: str, icon: str = "NONE") -> None:
    """A long message as several labels, the icon on the first."""
    column = layout.column(align=True)
    column.scale_y = 0.8
    for index, line in enumerate(wrapped(context, text)):
        column.label(text=line, icon=icon if index == 0 else "BLANK1")
