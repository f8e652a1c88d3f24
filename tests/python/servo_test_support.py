"""Shared by the servo tests: the real hapticut-servo binary, scenes, and the offline check.

Every test drives the installed binary (``hapticut.servo_path()``) over
loopback on ephemeral ports. ``offline_check`` replays what a recording says
the device did through the engine (``hapticut._core.Blade``) and compares.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import json
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
import pytest
from hapticut import _core, engine, servo_path
from hapticut.recording import Recording, read_recording
from hapticut.scenefile import BladeSpec, load_scene, save_scene
from hapticut.servo_client import ServoClient, ServoProcess

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
EXAMPLE_SCENES = sorted(EXAMPLES.glob("*.hapticut.msgpack"))
SPHERE = EXAMPLES / "sphere320.hapticut.msgpack"


# What a replay reproduces bit for bit of each record's blade block (with the proxies q, p
# and state); the force written is not among them: a replay device renders none.
REPLAYED_BLOCK_FIELDS = (
    "pose",
    "ideal_pose",
    "engine_force_N",
    "engine_torque_N_mm",
    "step_kind",
    "step_dt_s",
)


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


def wait_stopped(client: ServoClient, timeout_s: float = 60.0) -> list:
    """The stream frames received until the servo's run has stopped (at most timeout_s)."""
    frames = []
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        frames += client.poll_all()
        if client.status()["state"] == "stopped":
            break
        time.sleep(0.01)
    frames += client.poll_all()
    return frames


def tissue_scene(path: Path, source: Path = EXAMPLES / "finger.hapticut.msgpack") -> Path:
    """The scene with its skin and bone made flesh (drag 1 mm): the sim stroke cuts it."""
    scene = load_scene(source)
    materials = [
        dataclasses.replace(m, model="drag", drag_distance_mm=1.0, break_force_N=0.0)
        if m.model in ("membrane", "rigid")
        else m
        for m in scene.materials
    ]
    save_scene(dataclasses.replace(scene, materials=materials), path)
    return path


def two_blade_scene(path: Path) -> Path:
    """The sphere example with a second blade, "retractor" (20 points along y)."""
    scene = load_scene(SPHERE)
    retractor = BladeSpec("retractor", (0.0, -30.0, 0.0), (0.0, 30.0, 0.0), 20)
    save_scene(dataclasses.replace(scene, blades=[*scene.blades, retractor]), path)
    return path


def _write_with_coupling(path: Path, coupling: str, source: Path) -> Path:
    save_scene(load_scene(source), path)
    document = json.loads(path.read_text())
    for blade in document["blades"]:
        blade["coupling"] = coupling
    path.write_text(json.dumps(document))
    return path


@functools.cache
def _coupling_refusal() -> str:
    """Why this toolkit's scene reader refuses a blade's `coupling` ("" when it reads it:
    the setting came with the rigid blade's scene format)."""
    with tempfile.TemporaryDirectory() as directory:
        path = _write_with_coupling(Path(directory) / "probe.hapticut.json", "rigid", SPHERE)
        try:
            load_scene(path)
        except Exception as error:  # noqa: BLE001 - only the reader's refusal of the field
            if "coupling" not in str(error):
                raise
            return str(error)
    return ""


def scene_with_coupling(path: Path, coupling: str, source: Path = SPHERE) -> Path:
    """`source` with every blade's scene-file `coupling` set ("rigid" or "independent"),
    written as JSON at `path`. Skips the test when this toolkit's scene reader does not read
    a blade's coupling."""
    refusal = _coupling_refusal()
    if refusal:
        pytest.skip(f"the scene reader does not read a blade's coupling yet ({refusal})")
    return _write_with_coupling(path, coupling, source)


def independent_scene(path: Path, source: Path = SPHERE) -> Path:
    """`source` with independent points: a copy saying so where the reader reads a blade's
    coupling, else `source` itself (independent points are then the only blade)."""
    return source if _coupling_refusal() else _write_with_coupling(path, "independent", source)


def offline_check(
    scene_path: Path, recording: Recording, blade_name: str, settings: dict | None = None
) -> int:
    """Steps the engine offline through the recorded device poses and dts, with each tick's
    recorded stiffness and shading over the scene's settings per tick (fields in `settings`
    replaced), the blade of the recording's coupling; asserts every recorded q, p, ideal
    pose, engine force, transitions and rejection equals it bit for bit. Returns the ticks
    stepped."""
    scene, space = engine.load_space(scene_path)
    spec = next(b for b in scene.blades if b.name == blade_name)
    base = _core.runtime_settings(space)
    for name, value in (settings or {}).items():
        setattr(base, name, value)
    coupling = recording.coupling(blade_name)
    # The scene's orientation where its model has one (a rigid blade's; "free" by default).
    orientation = getattr(spec, "orientation", "free")
    blade = _core.Blade(
        space, list(spec.start_mm), list(spec.end_mm), spec.points, coupling, orientation
    )
    assert blade.coupling == coupling
    blade.settings = base
    records = recording.blade(blade_name)
    block = records["block"]
    cuts = recording.cut_blocks
    # The engine starts from the tets the recording started with cut.
    if len(cuts) and int(cuts["before_tick"][0]) > 0:
        blade.set_cuts(recording.cut_order(0)[: int(cuts["before_tick"][0])])
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
        assert np.array_equal(blade.ideal_pose, block["ideal_pose"][k]), (
            f"{blade_name}: ideal pose differs at tick {k}"
        )
        assert np.array_equal(tick["force_N"], block["engine_force_N"][k]), (
            f"{blade_name}: force differs at tick {k}"
        )
        assert tick["transitions"] == int(block["transitions"][k]), (
            f"{blade_name}: transitions differ at tick {k}"
        )
        assert bool(tick["rejected"]) == bool(block["engine_rejected"][k]), (
            f"{blade_name}: engine rejection differs at tick {k}"
        )
        if len(recording.blade_names) == 1 and cuts["generation"][k] == cuts["generation"][0]:
            assert len(blade.cut_order) == int(cuts["total"][k]), (
                f"{blade_name}: the tets cut differ at tick {k}"
            )
    if len(recording.blade_names) == 1 and len(cuts) and len(set(cuts["generation"])) == 1:
        assert np.array_equal(blade.cut_order, recording.cut_order()), "the cut order differs"
    return stepped


__all__ = [
    "EXAMPLES",
    "EXAMPLE_SCENES",
    "independent_scene",
    "SPHERE",
    "ServoClient",
    "ServoProcess",
    "bake",
    "connect",
    "offline_check",
    "read_recording",
    "run_servo",
    "scene_with_coupling",
    "stats_of",
    "tissue_scene",
    "two_blade_scene",
]
