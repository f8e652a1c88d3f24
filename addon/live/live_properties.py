"""What a scene stores for live sessions and bakes (``scene.hapticut_live``)."""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from . import device_list

# Blender keeps only pointers to the items' strings: every list handed out stays referenced
# here, one per (listing generation, stored choice missing from it).
_items_cache: dict[tuple[int, str], list[tuple[str, str, str, int]]] = {}


def device_items(settings, _context=None) -> list[tuple[str, str, str, int]]:
    """The Device menu (device_list.choices of the kept listing); a stored choice the
    listing does not hold (a file saved with a device not listed yet) stays offered."""
    stored = settings.device_choice
    choices = device_list.choices(device_list.cached())
    missing = "" if any(c.identifier == stored for c in choices) else stored
    key = (device_list.generation(), missing)
    if key not in _items_cache:  # Kept for good: a few small lists per Refresh devices.
        if missing:
            choices.append(
                device_list.Choice(missing, f"{missing} (not listed: Refresh devices)", missing)
            )
        _items_cache[key] = [
            (c.identifier, c.label, c.description, i) for i, c in enumerate(choices)
        ]
    return _items_cache[key]


def _get_device(settings) -> int:
    items = device_items(settings)
    return next((i[3] for i in items if i[0] == settings.device_choice), 0)


def _set_device(settings, value: int) -> None:
    items = device_items(settings)
    settings.device_choice = next((i[0] for i in items if i[3] == value), items[0][0])


def choice(settings) -> device_list.Choice:
    """The chosen menu item (its limits from the kept listing, {} without one)."""
    choices = device_list.choices(device_list.cached())
    found = next((c for c in choices if c.identifier == settings.device_choice), None)
    return found or device_list.Choice(settings.device_choice, settings.device_choice, "")


class HAPTICUT_PG_live(bpy.types.PropertyGroup):
    # The chosen item's identifier (what a .blend keeps; the menu below shows and sets it).
    device_choice: StringProperty(name="Device choice", default="VIEWPORT")
    device_mode: EnumProperty(
        name="Device",
        items=device_items,
        get=_get_device,
        set=_set_device,
        description="The servo device every blade is bound to (Refresh devices lists them)",
    )
    bridge_port: IntProperty(
        name="Bridge port",
        default=device_list.BRIDGE_DEFAULT_PORT,
        min=0,
        max=65535,
        description="The UDP bridge's port (bridge:port=N)",
    )
    device_error: StringProperty(name="Device listing error")
    custom_device: StringProperty(
        name="Device text",
        description="hapticut-servo --device KIND[:ARGS] for every blade",
        default="viewport",
    )
    rate_Hz: FloatProperty(
        name="Rate",
        default=1000.0,
        min=100.0,
        max=10000.0,
        unit="NONE",
        description="Servo rate (Hz)",
    )
    stiffness_N_per_mm: FloatProperty(
        name="Stiffness",
        default=0.0,
        min=0.0,
        max=10.0,
        description="Force per mm of lag, N/mm (0: the scene's)",
    )
    force_shading: BoolProperty(
        name="Force shading",
        default=False,
        description="Smooth the force across faces (when the servo offers it)",
    )
    max_force_N: FloatProperty(
        name="Max force",
        default=0.0,
        min=0.0,
        max=100.0,
        description="N (0: the device's; limits only lower it)",
    )
    max_torque_N_mm: FloatProperty(
        name="Max torque", default=0.0, min=0.0, max=10000.0, description="N mm (0: the device's)"
    )
    port: IntProperty(
        name="Port",
        default=0,
        min=0,
        max=65535,
        description="The servo's control port (0: any free one)",
    )
    realtime: BoolProperty(
        name="Real-time priority", default=True, description="Ask for SCHED_FIFO where permitted"
    )
    simulated_hand: BoolProperty(
        name="Simulated hand",
        default=False,
        description="Simulate stroke: a virtual hand holds the blade and feels the force "
        "(off: the blade follows its keyframes exactly)",
    )
    arrow_mm_per_N: FloatProperty(
        name="Arrow length",
        default=0.0,
        min=0.0,
        description="Force arrow length per newton (mm/N); 0: automatic, the stroke's peak "
        "force spans a fixed fraction of the scene's diagonal",
    )
    substeps: IntProperty(name="Cut rows per frame", default=2, min=1, max=16)
    bake_after_simulate: BoolProperty(name="Bake when done", default=True)
    # The last run (kept in the .blend).
    log_path: StringProperty(name="Servo log", subtype="FILE_PATH")
    recording_path: StringProperty(name="Recording", subtype="FILE_PATH")
    preview_path: StringProperty(name="Preview", subtype="FILE_PATH")
    bake_report: StringProperty(name="Bake")
    error: StringProperty(name="Error")


classes = (HAPTICUT_PG_live,)


def attach() -> None:
    bpy.types.Scene.hapticut_live = bpy.props.PointerProperty(type=HAPTICUT_PG_live)


def detach() -> None:
    del bpy.types.Scene.hapticut_live
