"""Hapticut for Blender: mark regions and blades, tetrahedralize, preview, export.

Thin by design (DESIGN.md): every algorithm runs in the ``hapticut`` toolkit, a child
process; this package is pure Python (standard library and Blender's numpy).
"""

from __future__ import annotations

import bpy

from . import build_job, operators, preferences, properties, ui

classes = (*properties.classes, *preferences.classes, *operators.classes, *ui.classes)


def register() -> None:
    for cls in classes:
        bpy.utils.register_class(cls)
    properties.attach()


def unregister() -> None:
    build_job.cancel_all()
    properties.detach()
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
