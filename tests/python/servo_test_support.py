"""Shared by the servo tests: the real hapticut-servo binary, scenes, and the offline check.

Every test drives the installed binary (``hapticut.servo_path()``) over
loopback on ephemeral ports. ``offline_check`` replays what a recording says
the device did through the engine (``hapticut._core.Blade``) and compares.
"""

from __future__ import annotations

import copy
import dataclasses
import subprocess
from pathlib import Path

import numpy as np
from hapticut import _core, engine, servo_path
from hapticut.recording import Recording, read_recording
from hapticut.scenefile import BladeSpec, load_scene, save_scene
from hapticut.servo_client import ServoClient, ServoProcess

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
EXAMPLE_SCENES = sorted(EXAMPLES.glob("*.hapticut.msgpack"))
SPHERE = EXAMPLES / "sphere320.hapticut.msgpack"


def independent_copy(scene_path: Path, folder: Path) -> Path:
    """The scene with every blade's points independent (the paper's blade), written in folder:
    for tests of a device path that needs each point's own force, such as a scripted hand that
    starts with the edge inside the sphere (a rigid blade there has no valid pose and no force)
    or force shading (applied to independent points only)."""
    scene = load_scene(scene_path)
    scene.blades = [dataclasses.replace(b, coupling="independent") for b in scene.blades]
    path = Path(folder) / scene_path.name
    save_scene(scene, path)
    return path


def run_servo(*args: str, timeout_s: float = 120.0) -> subprocess.CompletedProcess:
    """The servo to its end (no control channel): exit code, stdout, stderr."""
    return subprocess.run(
        [servo_path(), *args], capture_output=True, text=True, timeout=timeout_s, check=False
    )


def stats_of(stdout: str) -> dict:
    import json

    lines = [line for line in stdout.splitlines() if line.startswith("stats ")]
    assert lines, f"no stats line in:\n{stdout}"
    return json.loads(lines[-1][len("stats ") :])


def bake(scene: Path, record: Path, *devices: str, extra: tuple[str, ...] = ()) -> dict:
    """A sim stroke as fast as possible, recorded; returns the run's statistics."""
    args = [str(scene), "--as-fast-as-possible", "--exit-when-done", "--engage"]
    for d in devices:
        args += ["--device", d]
    result = run_servo(*args, "--record", str(record), *extra)
    assert result.returncode == 0, result.stderr
    return stats_of(result.stdout)


def connect(servo: ServoProcess, blade_names: list[str] | None = None) -> ServoClient:
    client = ServoClient(port=servo.port)
    client.hello()
    if blade_names:
        client.blade_names = blade_names
    return client


def two_blade_scene(path: Path) -> Path:
    """The sphere example with a second blade, "retractor" (20 points along y)."""
    scene = load_scene(SPHERE)
    retractor = BladeSpec("retractor", (0.0, -30.0, 0.0), (0.0, 30.0, 0.0), 20)
    save_scene(dataclasses.replace(scene, blades=[*scene.blades, retractor]), path)
    return path


def offline_check(
    scene_path: Path, recording: Recording, blade_name: str, settings: dict | None = None
) -> int:
    """Steps the engine offline through the recorded device poses and dts, with each tick's
    recorded stiffness and shading over the scene's settings per tick (fields in `settings`
    replaced); asserts every recorded q, p, engine force, transitions and rejection equals it
    bit for bit. Returns the ticks stepped."""
    scene, space = engine.load_space(scene_path)
    spec = next(b for b in scene.blades if b.name == blade_name)
    base = _core.runtime_settings(space)
    for name, value in (settings or {}).items():
        setattr(base, name, value)
    blade = engine.make_blade(space, spec, base)
    records = recording.blade(blade_name)
    block = records["block"]
    stepped = 0
    for k in range(len(records)):
        kind = int(block["step_kind"][k])
        if kind == 0:
            continue
        k_tick = float(block["stiffness_N_per_mm"][k])
        shaded = bool(block["force_shading"][k])
        if k_tick != base.stiffness_N_per_mm or shaded != base.force_shading:
            base = copy.copy(base)
            base.stiffness_N_per_mm = k_tick
            base.force_shading = shaded
            blade.settings = base
        pose = np.ascontiguousarray(block["pose"][k])
        if kind == 2:
            blade.reset(pose)
        tick = blade.step(pose, float(block["step_dt_s"][k]))
        stepped += 1
        assert np.array_equal(blade.q, records["q"][k]), f"{blade_name}: q differs at tick {k}"
        assert np.array_equal(blade.p, records["p"][k]), f"{blade_name}: p differs at tick {k}"
        assert np.array_equal(tick["force_N"], block["engine_force_N"][k]), (
            f"{blade_name}: force differs at tick {k}"
        )
        assert tick["transitions"] == int(block["transitions"][k]), (
            f"{blade_name}: transitions differ at tick {k}"
        )
        assert bool(tick["rejected"]) == bool(block["engine_rejected"][k]), (
            f"{blade_name}: engine rejection differs at tick {k}"
        )
    return stepped


__all__ = [
    "EXAMPLES",
    "EXAMPLE_SCENES",
    "SPHERE",
    "ServoClient",
    "ServoProcess",
    "bake",
    "connect",
    "offline_check",
    "read_recording",
    "run_servo",
    "stats_of",
    "two_blade_scene",
]
