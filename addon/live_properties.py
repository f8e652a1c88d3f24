"""What a scene stores for live sessions and bakes (``scene.hapticut_live``)."""

from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

DEVICE_MODES = (
    ("VIEWPORT", "Viewport", "Move the blade objects in the viewport (grab, rotate, playback)"),
    ("SIM", "Sim", "The servo's built-in simulated stroke (press, then slide)"),
    ("BLADES", "Blade devices", "Each blade's own Device field (HID profiles, UDP bridge, ...)"),
    ("CUSTOM", "Custom", "One --device text for every blade (e.g. sim:path.json)"),
)


class HAPTICUT_PG_live(bpy.types.PropertyGroup):
    device_mode: EnumProperty(name="Device", items=DEVICE_MODES, default="VIEWPORT")
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
        default=20.0,
        min=0.0,
        description="Force arrow length per newton (mm/N)",
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
