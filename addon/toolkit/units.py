"""Blender units to the toolkit's millimetres (the scene's unit scale honoured)."""

from __future__ import annotations


def mm_per_unit(scene) -> float:
    """One Blender unit in mm: unit_settings.scale_length metres."""
    return float(scene.unit_settings.scale_length) * 1000.0
