"""Hapticut for Blender: mark regions and blades, tetrahedralize, preview, export; then run
the scene live on the servo, simulate a keyframed stroke, bake it (docs/addon.md).

Thin by design (DESIGN.md): every algorithm runs in the ``hapticut`` toolkit, a child
process, or in its numpy-only modules loaded from the installed toolkit (toolkit_link); this
package is pure Python (standard library and Blender's numpy).
"""

from __future__ import annotations

import bpy

from . import build_job, live, live_properties, operators, preferences, properties, ui, ui_live

classes = (
    *properties.classes,
    *live_properties.classes,
    *preferences.classes,
    *operators.classes,
    *ui.classes,
    *ui_live.classes,
)


def register() -> None:
    for cls in classes:
        bpy.utils.register_class(cls)
    properties.attach()
    live_properties.attach()
    live.add_handlers()


def unregister() -> None:
    live.shutdown()
    live.remove_handlers()
    build_job.cancel_all()
    live_properties.detach()
    properties.detach()
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
