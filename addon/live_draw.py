"""Drawing the newest frame in the 3D views: the ideal points (proxies), the device points and
the force, through one ``gpu`` draw handler. The batches are built once per new frame
(``invalidate`` drops them) and reused by every redraw; the arrays are made by
``frame_geometry``, which needs no GPU (the tests call it in background mode)."""

from __future__ import annotations

import time

import bpy
import numpy as np

from . import live
from .units import mm_per_unit

PROXY_COLOUR = (0.1, 0.9, 1.0, 1.0)
DEVICE_COLOUR = (1.0, 0.3, 0.9, 1.0)
FORCE_COLOUR = (1.0, 0.8, 0.1, 1.0)
FORCE_MM_PER_N = 20.0

_handler = None
_batches: dict | None = None
_drawn_sequence = -1
draws = 0  # Redraws that used the cache (tests, measurements).
builds = 0  # Batches built.


def frame_geometry(frame, mm_per_blender_unit: float) -> dict[str, np.ndarray]:
    """Blender-unit arrays of a frame: ``proxies`` and ``devices`` (points), ``lines`` (each
    proxy to its device point, pairs) and ``force`` (one segment per blade)."""
    proxies, devices, forces = [], [], []
    for blade in frame.blades.values():
        q, p = np.asarray(blade["q"]), np.asarray(blade["p"])
        proxies.append(q)
        devices.append(p)
        centre = q.mean(axis=0)
        force = np.asarray(blade["block"]["engine_force_N"]) * FORCE_MM_PER_N
        forces.append(np.stack([centre, centre + force]))
    scale = 1.0 / mm_per_blender_unit
    q = np.concatenate(proxies) * scale if proxies else np.zeros((0, 3))
    p = np.concatenate(devices) * scale if devices else np.zeros((0, 3))
    lines = np.stack([q, p], 1).reshape(-1, 3)
    force = np.concatenate(forces) * scale if forces else np.zeros((0, 3))
    return {
        "proxies": q.astype(np.float32),
        "devices": p.astype(np.float32),
        "lines": lines.astype(np.float32),
        "force": force.astype(np.float32),
    }


def invalidate() -> None:
    global _batches
    _batches = None


def _build(frame, scene):
    global builds
    import gpu
    from gpu_extras.batch import batch_for_shader

    shader = gpu.shader.from_builtin("UNIFORM_COLOR")
    geometry = frame_geometry(frame, mm_per_unit(scene))
    builds += 1
    return shader, {
        "proxies": (batch_for_shader(shader, "POINTS", {"pos": geometry["proxies"]}), PROXY_COLOUR),
        "devices": (
            batch_for_shader(shader, "POINTS", {"pos": geometry["devices"]}),
            DEVICE_COLOUR,
        ),
        "lines": (batch_for_shader(shader, "LINES", {"pos": geometry["lines"]}), DEVICE_COLOUR),
        "force": (batch_for_shader(shader, "LINES", {"pos": geometry["force"]}), FORCE_COLOUR),
    }


def draw() -> None:
    """The draw handler (POST_VIEW): the cached batches of the newest frame."""
    global _batches, _drawn_sequence, draws
    session = live.current()
    if session is None or session.frame is None:
        return
    import gpu

    if _batches is None or _drawn_sequence != session.frame.sequence:
        _batches = _build(session.frame, bpy.context.scene)
        _drawn_sequence = session.frame.sequence
        session.frames_drawn += 1
        # The age of the drawn frame: servo time (CLOCK_MONOTONIC, as time.monotonic) to now.
        session.drawn_ages_s.append(time.monotonic() - float(session.frame.header["servo_time_s"]))
    shader, batches = _batches
    gpu.state.point_size_set(5.0)
    gpu.state.line_width_set(2.0)
    for batch, colour in batches.values():
        shader.uniform_float("color", colour)
        batch.draw(shader)
    draws += 1


def add_handler() -> None:
    global _handler
    if _handler is None:
        _handler = bpy.types.SpaceView3D.draw_handler_add(draw, (), "WINDOW", "POST_VIEW")


def remove_handler() -> None:
    global _handler
    if _handler is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_handler, "WINDOW")
        _handler = None
    invalidate()


def handler_added() -> bool:
    return _handler is not None


def tag_redraw() -> None:
    manager = bpy.context.window_manager
    for window in manager.windows if manager is not None else ():
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()
