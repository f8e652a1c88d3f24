"""The engine from Python: a Space from a scene, blades, strokes.

    from hapticut import engine
    scene, space = engine.load_space("examples/sphere320.hapticut.msgpack")
    blade = engine.make_blade(space, scene.blades[0])
    poses = engine.straight_stroke([0, -60, 0], [0, 60, 0], speed_mm_per_s=100)
    result = blade.run(poses, dt_s=0.001)      # one C++ call for the whole stroke
    result["force_N"]                          # (ticks, 3) summed force per tick

    settings = blade.settings                  # settings per tick (RuntimeSettings)
    settings.force_shading = True              # changed between ticks, no new Space
    blade.settings = settings

The C++ classes (``hapticut._core``) are re-exported: ``Space``, ``ProxySet``,
``Blade``, ``ProxyState``, ``RuntimeSettings``. A ProxySet or Blade keeps its
Space alive; their long calls (``run``, ``step`` of many points) release the GIL,
and one object is used by one thread at a time (another gets RuntimeError).
"""

from __future__ import annotations

import os
from dataclasses import asdict

import numpy as np

from hapticut import _core
from hapticut.scenefile import BladeSpec, Scene, load_scene

Space = _core.Space
ProxySet = _core.ProxySet
Blade = _core.Blade
ProxyState = _core.ProxyState
RuntimeSettings = _core.RuntimeSettings
MeshError = _core.MeshError
STATE_NAMES = _core.STATE_NAMES
IDENTITY_ROTATION = (1.0, 0.0, 0.0, 0.0)


def space_from_scene(scene: Scene) -> _core.Space:
    """The engine's Space for a scene (validates the mesh; MeshError names the index)."""
    return _core.Space(
        np.ascontiguousarray(scene.vertices, dtype=np.float64),
        np.ascontiguousarray(scene.tets, dtype=np.int32),
        np.ascontiguousarray(scene.tet_materials, dtype=np.int32),
        [asdict(m) for m in scene.materials],
        stiffness_N_per_mm=scene.stiffness_N_per_mm,
        servo_rate_Hz=scene.servo_rate_Hz,
        max_transitions_per_tick=scene.max_transitions_per_tick,
        capped_tick_force_N=scene.safety.capped_tick_force_N,
        tolerance_mm=scene.tolerance_mm,
    )


def load_space(path: str | os.PathLike) -> tuple[Scene, _core.Space]:
    """Read a scene file and build its Space."""
    scene = load_scene(path)
    return scene, space_from_scene(scene)


def make_blade(
    space: _core.Space, spec: BladeSpec, settings: _core.RuntimeSettings | None = None
) -> _core.Blade:
    """A blade of the scene's spec; settings per tick default to the scene's own."""
    blade = _core.Blade(
        space,
        list(spec.start_mm),
        list(spec.end_mm),
        spec.points,
        coupling=spec.coupling,
        orientation=spec.orientation,
    )
    if settings is not None:
        blade.settings = settings
    return blade


def straight_stroke(
    start_mm,
    end_mm,
    speed_mm_per_s: float,
    rate_Hz: float = 1000.0,
    rotation=IDENTITY_ROTATION,
) -> np.ndarray:
    """Poses (M, 7) = (x, y, z, qw, qx, qy, qz) moving the tool origin from start to end."""
    start = np.asarray(start_mm, dtype=np.float64)
    end = np.asarray(end_mm, dtype=np.float64)
    length = float(np.linalg.norm(end - start))
    if speed_mm_per_s <= 0 or rate_Hz <= 0:
        raise ValueError("speed_mm_per_s and rate_Hz must be positive")
    ticks = max(2, int(round(length / speed_mm_per_s * rate_Hz)) + 1)
    s = np.linspace(0.0, 1.0, ticks)[:, None]
    poses = np.empty((ticks, 7))
    poses[:, :3] = start + (end - start) * s
    poses[:, 3:] = np.asarray(rotation, dtype=np.float64)
    return poses


def state_counts(states: np.ndarray) -> dict[str, int]:
    """How many proxies are in each state (states: the uint8 array of ProxySet/Blade.state)."""
    counts = np.bincount(np.asarray(states, dtype=np.int64), minlength=len(STATE_NAMES))
    return {name: int(counts[i]) for i, name in enumerate(STATE_NAMES)}
