"""Undo steps for what a timer changes (the preview at the end of a build or an import, a
bake). Blender pushes a step after an operator that has 'UNDO' in its options, but
Tetrahedralize, Import Scene, Simulate Stroke and Bake return long before their timers edit
the scene: without a step of its own that edit would be undone together with whatever
operator came before it.
"""

from __future__ import annotations

import contextlib

import bpy


def push(message: str) -> None:
    """An undo step named message for the scene as it is now. None in background mode: a
    script or a render farm has no one to press Ctrl+Z, and every step is a copy of the
    file's data in memory."""
    if bpy.app.background:
        return
    # No undo stack in this context: the edit stays, without a step of its own.
    with contextlib.suppress(RuntimeError):
        bpy.ops.ed.undo_push(message=message)
