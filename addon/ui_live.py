"""The sidebar's live panels: the session (device, settings, Start/Stop, Engage, status) and
the bake (Simulate stroke, Record, Bake, Clear)."""

from __future__ import annotations

import json

import bpy

from . import live, live_draw


def status_lines(session) -> list[str]:
    """What the panel says about the session (also what the tests read)."""
    if session is None:
        error = live.last_error()
        return [f"not connected: {error}" if error else "not connected"]
    if session.state == "lost":
        return [f"servo lost: {session.error}", "Start to recover"]
    status = session.status
    lines = [f"connected ({session.state}), servo {status.get('state', '?')}"]
    if status:
        compute = status.get("compute_us", {})
        lines.append(
            f"{status.get('rate_Hz', 0):g} Hz, {status.get('ticks', 0)} ticks, "
            f"late {status.get('late_ticks', 0)}, compute p99 {compute.get('p99', 0):.0f} us"
        )
        for blade in status.get("blades", []):
            force = sum(f * f for f in blade.get("force_N", [0, 0, 0])) ** 0.5
            events = ", ".join(
                f"{k} {v}"
                for k, v in blade.get("events", {}).items()
                if k not in ("engaged", "ramping")
            )
            lines.append(
                f"{blade['name']} ({blade.get('kind', '?')}, "
                f"{blade.get('device_status', '?')}): {force:.2f} N"
            )
            if events:
                lines.append(f"  safety events: {events}")
        recording = status.get("recording", {})
        if recording.get("active"):
            lines.append(f"recording: {recording.get('written', 0)} ticks")
    frame = session.frame
    if frame is not None:
        for name, blade in frame.blades.items():
            counts = blade["block"]["state_counts"]
            lines.append(
                f"{name}: TET {counts[0]} FACE {counts[1]} EDGE {counts[2]} "
                f"VERTEX {counts[3]} OUTSIDE {counts[4]}"
            )
    if session.error:
        lines.append(f"error: {session.error}")
    return lines


class HAPTICUT_PT_live(bpy.types.Panel):
    bl_label = "Live Session"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Hapticut"
    bl_parent_id = "HAPTICUT_PT_scene"

    def draw(self, context):
        layout = self.layout
        settings = context.scene.hapticut_live
        layout.prop(settings, "device_mode")
        if settings.device_mode == "CUSTOM":
            layout.prop(settings, "custom_device")
        for name in (
            "rate_Hz",
            "stiffness_N_per_mm",
            "force_shading",
            "max_force_N",
            "max_torque_N_mm",
            "port",
            "realtime",
        ):
            layout.prop(settings, name)
        session = live.current()
        row = layout.row()
        row.operator("hapticut.start_servo", icon="PLAY")
        row.operator("hapticut.stop_servo", icon="PAUSE")
        row = layout.row()
        row.operator("hapticut.go_live", icon="HAND")
        row.operator("hapticut.engage_servo", text="Engage").engaged = True
        row.operator("hapticut.engage_servo", text="Release").engaged = False
        for line in status_lines(session):
            icon = "ERROR" if line.startswith(("servo lost", "error", "not connected:")) else "NONE"
            layout.label(text=line, icon=icon)
        if settings.error:
            layout.label(text=settings.error, icon="ERROR")
        if settings.log_path:
            layout.operator("hapticut.open_servo_log", icon="TEXT")
        if live_draw.handler_added():
            layout.label(text="drawing proxies (cyan), device points (pink), force (yellow)")


class HAPTICUT_PT_bake(bpy.types.Panel):
    bl_label = "Stroke and Bake"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Hapticut"
    bl_parent_id = "HAPTICUT_PT_scene"

    def draw(self, context):
        layout = self.layout
        settings = context.scene.hapticut_live
        for name in ("simulated_hand", "bake_after_simulate", "arrow_mm_per_N", "substeps"):
            layout.prop(settings, name)
        layout.operator("hapticut.simulate_stroke", icon="ANIM")
        row = layout.row()
        row.operator("hapticut.record_live", icon="REC")
        row.operator("hapticut.bake_recording", icon="KEYFRAME")
        row.operator("hapticut.clear_bake", icon="TRASH")
        if settings.recording_path:
            layout.label(text=f"recording: {settings.recording_path}")
        if settings.bake_report:
            report = json.loads(settings.bake_report)
            layout.label(
                text=f"baked {report['frames']} frames from {report['ticks']} ticks "
                f"in {report['seconds']:.1f} s"
            )
            for name, blade in report["blades"].items():
                layout.label(
                    text=f"{name}: {blade['cut_faces']} cut faces, "
                    f"max force {blade['max_force_N']:.2f} N"
                )


classes = (HAPTICUT_PT_live, HAPTICUT_PT_bake)
