"""The sidebar's live panels: the session (device, settings, Start/Stop, Engage, status) and
the bake (Simulate stroke, Record, Bake, Clear)."""

from __future__ import annotations

import json

import bpy

from ..background import jobs
from ..live import device_list, live_draw, live_link, live_properties, live_session
from .sidebar import SidebarSubpanel, draw_properties, draw_status

SESSION_SETTINGS = (
    "rate_Hz",
    "stiffness_N_per_mm",
    "force_shading",
    "max_force_N",
    "max_torque_N_mm",
    "port",
    "realtime",
)


def status_lines(session) -> list[str]:
    """What the panel says about the session (also what the tests read)."""
    job = jobs.current()
    doing = [f"{job.name}: {job.stage}"] if job is not None else []
    if session is None:
        error = live_link.last_error()
        return [f"not connected: {error}" if error else "not connected", *doing]
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
    timer_age = live_session.age_text(session.stream_frame_ages_s)
    if timer_age:
        drawn_age = live_session.age_text(session.drawn_ages_s)
        lines.append(
            f"frame age p50 / p99: {timer_age} at the timer"
            + (f", {drawn_age} drawn" if drawn_age else "")
        )
    frame = session.stream_frame
    if frame is not None:
        for name, blade in frame.blades.items():
            counts = blade["block"]["state_counts"]
            lines.append(
                f"{name}: TET {counts[0]} FACE {counts[1]} EDGE {counts[2]} "
                f"VERTEX {counts[3]} OUTSIDE {counts[4]}"
            )
    cuts = session.cut_set
    if cuts is not None and cuts.generation is not None:
        lines.append(f"cut: {len(cuts.order):,} tets (Reset Cuts: fresh tissue)")
    if session.error:
        lines.append(f"error: {session.error}")
    return lines + doing


BAKE_SETTINGS = ("simulated_hand", "bake_after_simulate", "arrow_mm_per_N", "substeps")


def bake_lines(report: dict) -> list[str]:
    """What the bake panel says of the range baked and the arrow's scale (the tests read it)."""
    lines = []
    if report.get("unbaked_frames"):
        first, last = report["frame_range"]
        lines.append(
            f"keys on frames {first}-{last}: the recording's last {report['unbaked_s']:.2f} s "
            f"({report['unbaked_frames']} frames) lie after the scene's end, not baked"
        )
    if "arrow_mm_per_N" in report:
        lines.append(f"force arrow {report['arrow_mm_per_N']:.3g} mm/N")
    return lines


def draw_device(layout, settings) -> None:
    """The device menu with *Refresh devices*, its options, its limits and what of the
    settings lies above them (Go Live and Simulate stroke refuse it)."""
    row = layout.row()
    row.prop(settings, "device_mode")
    row.operator("hapticut.refresh_devices", text="", icon="FILE_REFRESH")
    if settings.device_choice == "CUSTOM":
        layout.prop(settings, "custom_device")
    elif settings.device_choice == "BRIDGE":
        layout.prop(settings, "bridge_port")
    draw_status(layout, error=settings.device_error)
    if settings.device_choice in ("BLADES", "CUSTOM"):
        return
    limits = live_properties.choice(settings).limits
    if not limits:
        layout.label(text="device limits: Refresh devices to read them", icon="INFO")
        return
    layout.label(text=f"device limits: {device_list.limits_text(limits)}")
    requested = live_link.requested_settings(settings)
    listed_Hz = device_list.listed_rate()
    if listed_Hz != settings.rate_Hz and limits.get("max_stiffness_N_per_mm", 0) > 0:
        layout.label(
            text=f"stiffness limit read at {listed_Hz:g} Hz: Refresh devices for "
            f"{settings.rate_Hz:g} Hz (Go Live reads it)",
            icon="INFO",
        )
    springs = live_link.blade_springs(settings.id_data)  # The scene the settings belong to.
    for problem in device_list.settings_problems(requested, limits, listed_Hz, springs):
        layout.label(text=f"{problem}: Go Live refuses it", icon="ERROR")


class HAPTICUT_PT_live(SidebarSubpanel, bpy.types.Panel):
    bl_label = "Live Session"

    def draw(self, context):
        layout = self.layout
        settings = context.scene.hapticut_live
        draw_device(layout, settings)
        draw_properties(layout, settings, SESSION_SETTINGS)
        session = live_link.current()
        row = layout.row()
        row.operator("hapticut.start_servo", icon="PLAY")
        row.operator("hapticut.stop_servo", icon="PAUSE")
        row = layout.row()
        row.operator("hapticut.go_live", icon="HAND")
        row.operator("hapticut.engage_servo", text="Engage").engaged = True
        row.operator("hapticut.engage_servo", text="Release").engaged = False
        layout.operator("hapticut.reset_cuts", icon="LOOP_BACK")
        for line in status_lines(session):
            icon = "ERROR" if line.startswith(("servo lost", "error", "not connected:")) else "NONE"
            layout.label(text=line, icon=icon)
        if jobs.current() is not None:
            layout.operator("hapticut.cancel_job", icon="CANCEL")
        draw_status(layout, error=settings.error)
        if settings.log_path:
            layout.operator("hapticut.open_servo_log", icon="TEXT")
        if live_draw.handler_added():
            layout.label(
                text="drawing proxies (cyan), device points (pink), force (yellow), "
                "the knife at its ideal pose (green)"
            )


class HAPTICUT_PT_bake(SidebarSubpanel, bpy.types.Panel):
    bl_label = "Stroke and Bake"

    def draw(self, context):
        layout = self.layout
        settings = context.scene.hapticut_live
        draw_properties(layout, settings, BAKE_SETTINGS)
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
            for line in bake_lines(report):
                layout.label(text=line)
            if report.get("truncated"):
                layout.label(text=report["truncated"], icon="ERROR")
            for name, blade in report["blades"].items():
                layout.label(
                    text=f"{name}: {blade['cut_faces']} cut faces, "
                    f"max force {blade['max_force_N']:.2f} N"
                )


classes = (HAPTICUT_PT_live, HAPTICUT_PT_bake)
