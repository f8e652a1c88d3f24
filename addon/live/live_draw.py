"""Drawing the newest stream frame in the 3D views: the ideal points (proxies), the device
points, the force and the knife at its ideal pose (a wireframe ghost of each blade object's
mesh), through one ``gpu`` draw handler. The batches are built once per new stream frame
(``invalidate`` drops them) and reused by every redraw; the arrays are made by
``stream_frame_geometry``, which needs no GPU (the tests call it in background mode)."""

from __future__ import annotations

import time

import bpy
import numpy as np

from ..toolkit.units import mm_per_unit
from . import live_session, stroke_path

PROXY_COLOUR = (0.1, 0.9, 1.0, 1.0)
DEVICE_COLOUR = (1.0, 0.3, 0.9, 1.0)
FORCE_COLOUR = (1.0, 0.8, 0.1, 1.0)
KNIFE_COLOUR = (0.3, 1.0, 0.3, 1.0)
FORCE_MM_PER_N = 20.0

_handler = None
_batches: dict | None = None
_drawn_sequence = -1
draws = 0  # Redraws that used the cache (tests, measurements).
builds = 0  # Batches built.
# Per blade object: (its mesh's identity, its edges' vertices in object coordinates, (2E, 3)
# LINES pairs); read again only when the mesh changes, not at every frame.
_edge_cache: dict[str, tuple[tuple, np.ndarray]] = {}


def pose_matrix(pose, mm_per_blender_unit: float) -> np.ndarray:
    """The 4x4 matrix, in Blender units, of a pose (x, y, z (mm), qw, qx, qy, qz)."""
    w, x, y, z = np.asarray(pose[3:7], np.float64) / np.linalg.norm(pose[3:7])
    matrix = np.eye(4)
    matrix[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]
    matrix[:3, 3] = np.asarray(pose[:3], np.float64) / mm_per_blender_unit
    return matrix


def object_edges(obj) -> np.ndarray:
    """The object's mesh edges as LINES pairs in object coordinates, (2E, 3); cached per
    object until its mesh changes (another mesh, other vertex or edge counts)."""
    mesh = obj.data
    key = (mesh.name_full, len(mesh.vertices), len(mesh.edges))
    cached = _edge_cache.get(obj.name_full)
    if cached is not None and cached[0] == key:
        return cached[1]
    vertices = np.empty(3 * len(mesh.vertices), np.float64)
    mesh.vertices.foreach_get("co", vertices)
    indices = np.empty(2 * len(mesh.edges), np.int64)
    mesh.edges.foreach_get("vertices", indices)
    edges = vertices.reshape(-1, 3)[indices]
    _edge_cache[obj.name_full] = (key, edges)
    return edges


def ghost_lines(obj, ideal_pose, mm_per_blender_unit: float) -> np.ndarray:
    """The object's edges moved from its own pose (the one a viewport device sends,
    ``stroke_path.pose_of``) to the ideal pose: M(ideal) M(object pose)^-1 matrix_world, its
    scale kept (the blade's edge is in the scaled object frame). (2E, 3), Blender units."""
    mm = mm_per_blender_unit
    world = np.array(obj.matrix_world, np.float64)
    own = pose_matrix(stroke_path.pose_of(obj.matrix_world, mm), mm)
    moved = pose_matrix(ideal_pose, mm) @ np.linalg.inv(own) @ world
    edges = object_edges(obj)
    return edges @ moved[:3, :3].T + moved[:3, 3]


def stream_frame_geometry(frame, mm_per_blender_unit: float, objects=None) -> dict[str, np.ndarray]:
    """Blender-unit arrays of a frame: ``proxies`` and ``devices`` (points), ``lines`` (each
    proxy to its device point, pairs), ``force`` (one segment per blade) and ``knife`` (LINES
    pairs: each blade's mesh object, found by name in objects, at its ideal pose)."""
    proxies, devices, forces, knives = [], [], [], []
    for name, blade in frame.blades.items():
        obj = objects.get(name) if objects is not None else None
        if obj is not None and obj.type == "MESH":
            ideal = np.asarray(blade["block"]["ideal_pose"], np.float64)
            knives.append(ghost_lines(obj, ideal, mm_per_blender_unit))
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
    knife = np.concatenate(knives) if knives else np.zeros((0, 3))
    return {
        "proxies": q.astype(np.float32),
        "devices": p.astype(np.float32),
        "lines": lines.astype(np.float32),
        "force": force.astype(np.float32),
        "knife": knife.astype(np.float32),
    }


def invalidate() -> None:
    global _batches
    _batches = None


def _build(frame, scene):
    global builds
    import gpu
    from gpu_extras.batch import batch_for_shader

    shader = gpu.shader.from_builtin("UNIFORM_COLOR")
    geometry = stream_frame_geometry(frame, mm_per_unit(scene), scene.objects)
    builds += 1
    return shader, {
        "proxies": (batch_for_shader(shader, "POINTS", {"pos": geometry["proxies"]}), PROXY_COLOUR),
        "devices": (
            batch_for_shader(shader, "POINTS", {"pos": geometry["devices"]}),
            DEVICE_COLOUR,
        ),
        "lines": (batch_for_shader(shader, "LINES", {"pos": geometry["lines"]}), DEVICE_COLOUR),
        "force": (batch_for_shader(shader, "LINES", {"pos": geometry["force"]}), FORCE_COLOUR),
        "knife": (batch_for_shader(shader, "LINES", {"pos": geometry["knife"]}), KNIFE_COLOUR),
    }


def draw(current) -> None:
    """The draw handler (POST_VIEW): the cached batches of the newest frame of the session
    ``current()`` gives (the live link's: it passes its own, so this module needs none)."""
    global _batches, _drawn_sequence, draws
    session = current()
    if session is None or session.stream_frame is None:
        return
    import gpu

    if _batches is None or _drawn_sequence != session.stream_frame.sequence:
        _batches = _build(session.stream_frame, bpy.context.scene)
        _drawn_sequence = session.stream_frame.sequence
        session.stream_frames_drawn += 1
        # The age of the drawn frame: servo time (CLOCK_MONOTONIC, as time.monotonic) to now.
        age_s = live_session.stream_frame_age_s(session.stream_frame, time.monotonic())
        if age_s is not None:
            session.drawn_ages_s.append(age_s)
    shader, batches = _batches
    gpu.state.point_size_set(5.0)
    gpu.state.line_width_set(2.0)
    for batch, colour in batches.values():
        shader.uniform_float("color", colour)
        batch.draw(shader)
    draws += 1


def add_handler(current) -> None:
    """Draw the frames of the session current() gives, in every 3D view."""
    global _handler
    if _handler is None:
        _handler = bpy.types.SpaceView3D.draw_handler_add(draw, (current,), "WINDOW", "POST_VIEW")


def remove_handler() -> None:
    global _handler
    if _handler is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_handler, "WINDOW")
        _handler = None
    invalidate()
    _edge_cache.clear()


def handler_added() -> bool:
    return _handler is not None


def tag_redraw() -> None:
    manager = bpy.context.window_manager
    for window in manager.windows if manager is not None else ():
        for area in window.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()
