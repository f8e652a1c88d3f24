"""Hapticut for Blender: mark regions and blades, tetrahedralize, preview, export; then run
the scene live on the servo, simulate a keyframed stroke, bake it (docs/addon.md).

Thin by design (docs/decisions.md, "The toolkit runs outside Blender"): every algorithm
runs in the ``hapticut`` toolkit, a child process, or in its numpy-only modules loaded from
the installed toolkit (toolkit_link); this package is pure Python (standard library and
Blender's numpy).
"""

from __future__ import annotations

import bpy

from . import operators
from .authoring import build_job, file_handlers, properties
from .background import jobs
from .live import live_link, live_properties
from .toolkit import preferences, runner
from .ui import live_panels, scene_panels

classes = (
    *properties.classes,
    *live_properties.classes,
    *preferences.classes,
    *operators.classes,
    *scene_panels.classes,
    *live_panels.classes,
)


def register() -> None:
    for cls in classes:
        bpy.utils.register_class(cls)
    properties.attach()
    live_properties.attach()
    live_link.add_handlers()
    file_handlers.add_handlers()
    if not bpy.app.background:  # Read the material table once, soon after startup.
        bpy.app.timers.register(_read_material_table, first_interval=1.0)


def _read_material_table():
    """A one-shot timer: a missing toolkit shows in the preferences, not as an error here."""
    prefs = preferences.preferences()
    try:
        preferences.material_table()
    except runner.ToolkitError as error:
        if prefs is not None:
            prefs.toolkit_error = str(error)
    return None


def unregister() -> None:
    jobs.cancel_all()
    jobs.stop_timer()
    live_link.stop()
    live_link.remove_handlers()
    file_handlers.remove_handlers()
    if bpy.app.timers.is_registered(_read_material_table):
        bpy.app.timers.unregister(_read_material_table)
    build_job.cancel_all()
    live_properties.detach()
    properties.detach()
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
