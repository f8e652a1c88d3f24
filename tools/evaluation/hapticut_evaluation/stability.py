"""Stability where methods fail: method x scenario, pass or fail, and the figure
behind each verdict. A fall-through is a proxy deeper inside the true rigid
region than the method's own resolution allows (0 for the tet proxy and the
god-object, which see the same facets; a cell diagonal for voxels)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from hapticut import _core

from hapticut_evaluation import _baselines, meshes, methods, paths
from hapticut_evaluation.accuracy import sphere_inside


@dataclass
class Scenario:
    name: str
    scene: meshes.TetScene
    path: np.ndarray  # (ticks, N, 3)
    dt_s: float
    inside: object = None  # Analytic solid for the voxel grid, else the tets.
    wrong_side: object = None  # q -> bool array: beyond a wall's mid-plane.
    voxel_sizes: tuple = (4.0, 1.0, 0.25)


def _air_start(scene: meshes.TetScene) -> np.ndarray:
    air = np.flatnonzero(scene.labels == meshes.AIR)
    return scene.vertices[scene.tets[air[0]]].mean(axis=0)


def _walk_around(
    start: np.ndarray, steps: int, step_mm: float, half_mm: float, points: int = 4, seed: int = 5
) -> np.ndarray:
    walk = paths.random_walk(steps, points=points, step_mm=step_mm, seed=seed, half_mm=half_mm)
    walk -= walk[0] - start  # Start every walk at `start` (in air).
    return np.ascontiguousarray(np.clip(walk, -half_mm, half_mm))


def wall_scenario() -> Scenario:
    """A rigid wall 1 mm thick (z in [-0.5, 0.5]); the device point crosses it in one tick."""
    xs = ys = [-20.0, -10.0, 0.0, 10.0, 20.0]
    zs = [-20.0, -10.0, -0.5, 0.5, 10.0, 20.0]
    scene = meshes.grid_scene("wall 1 mm", xs, ys, zs, ((-21, -21, -0.5), (21, 21, 0.5)))
    xy = np.array([[1.3, 2.1], [-3.7, 0.4], [5.0, 5.0], [0.0, 0.0]])
    path = np.zeros((40, len(xy), 3))
    path[:, :, :2] = xy
    path[:, :, 2] = np.where(np.arange(40) < 20, 3.0, -3.0)[:, None]
    return Scenario(
        "1 mm wall crossed in one tick", scene, path, 0.001, wrong_side=lambda q: q[..., 2] < 0.0
    )


def fan_scenario(name: str, mesh, steps: int) -> Scenario:
    scene = meshes.fan_scene(name, mesh)
    start = _air_start(scene)
    return Scenario(
        name, scene, _walk_around(start, steps, 0.5, 9.0), 0.001, voxel_sizes=(1.0, 0.25)
    )


def sliver_scenario(steps: int) -> Scenario:
    """Layers 1 um thin (flat tets) and jittered cells around a rigid slab."""
    xs = ys = [-10.0, -5.0, 0.0, 5.0, 10.0]
    zs = [-10.0, -2.0, -1.001, -1.0, 1.0, 1.001, 2.0, 10.0]
    scene = meshes.grid_scene(
        "slivers", xs, ys, zs, ((-11, -11, -1.001), (11, 11, 1.001)), jitter=0.3, seed=4
    )
    start = np.array([0.3, 0.2, 6.0])
    return Scenario(
        "sliver tets (1 um layers, jitter)",
        scene,
        _walk_around(start, steps, 1.0, 9.5),
        0.001,
        voxel_sizes=(1.0, 0.25),
    )


def exact_points_scenario() -> Scenario:
    """A rigid block (-5, 5)^3 in air; device points aimed exactly at a block
    vertex, an edge, a face point and a face's centre, and at mesh vertices,
    started exactly on them."""
    grid = [-10.0, -5.0, 0.0, 5.0, 10.0]
    scene = meshes.grid_scene("block", grid, grid, grid, ((-5, -5, -5), (5, 5, 5)))
    targets = np.array([[5, 5, 5], [5, 5, 0], [5, 0, 0], [5, 2.5, 2.5], [5, 5, 2.5]], float)
    dirs = targets / np.linalg.norm(targets, axis=1)[:, None]
    ticks = 120
    s = np.concatenate([np.linspace(4.0, 0.0, 40), np.linspace(0.0, -3.0, 40), np.full(40, -3.0)])
    path = targets[None] + s[:, None, None] * dirs[None]
    # Two more: slide exactly along a block edge and across a face, on the surface.
    line = np.linspace(-4.0, 4.0, ticks)
    edge = np.stack([np.full(ticks, 5.0), np.full(ticks, 5.0), line], axis=1)
    face = np.stack([np.full(ticks, 5.0), line, line * 0.5], axis=1)
    path = np.concatenate([path, edge[:, None], face[:, None]], axis=1)
    path[0, 5:] += [0.0, 0.0, 0.0]
    return Scenario(
        "points exactly on faces, edges, vertices", scene, np.ascontiguousarray(path), 0.001
    )


def sphere_stroke_scenario(cache: Path, faces: int, rate_hz: float) -> Scenario:
    scene = meshes.sphere_in_cube(faces, cache)
    path, _ = paths.press_and_slide(1.0 / rate_hz)
    return Scenario(
        f"press-and-slide at {rate_hz:g} Hz ({faces}-face sphere)",
        scene,
        path,
        1.0 / rate_hz,
        inside=sphere_inside,
        voxel_sizes=(4.0, 1.0, 0.25),
    )


def random_walk_scenario(cache: Path, faces: int, steps: int) -> Scenario:
    scene = meshes.sphere_in_cube(faces, cache)
    walk = paths.random_walk(steps, points=1, step_mm=1.0, seed=11)
    return Scenario(
        f"random walk, {steps:.0e} steps ({faces}-face sphere)",
        scene,
        walk,
        0.001,
        inside=sphere_inside,
        voxel_sizes=(4.0, 1.0, 0.25),
    )


def evaluate_scenario(scenario: Scenario, families=None) -> list[dict]:
    space = scenario.scene.space()
    rows = []
    families = families or (methods.TET, methods.SHADED, methods.GOD, methods.VOXEL)
    for method in methods.methods_for(
        scenario.scene,
        space,
        families=families,
        voxel_sizes=scenario.voxel_sizes,
        inside=scenario.inside,
    ):
        n = scenario.path.shape[1]
        method_set = method.make(n)
        method_set.reset(np.ascontiguousarray(scenario.path[0]))
        result = method_set.run(scenario.path, scenario.dt_s, check=True, timing_repeats=0)
        q = result["q"]
        finite = bool(np.all(np.isfinite(q)) and np.all(np.isfinite(result["force_N"])))
        depth = _baselines.rigid_depth(space, np.ascontiguousarray(q.reshape(-1, 3)))
        max_depth = float(depth.max()) if depth.size else 0.0
        deep = int((depth > method.allowance_mm).sum())
        wrong = int(scenario.wrong_side(q).sum()) if scenario.wrong_side is not None else 0
        failures = int(result["invariant_failures"])
        ok = finite and deep == 0 and wrong == 0 and failures == 0
        figure = (
            f"max depth {max_depth:.3g} mm (allowed {method.allowance_mm:.2g}); "
            f"{deep} deep ticks; {wrong} beyond the wall; {failures} invariant failures"
        )
        if not finite:
            figure = "NaN or inf in q or force; " + figure
        rows.append(
            {
                "scenario": scenario.name,
                "method": method.label,
                "family": method.family,
                "verdict": "pass" if ok else "FAIL",
                "max_depth_mm": max_depth,
                "deep_ticks": deep,
                "wrong_side_ticks": wrong,
                "invariant_failures": failures,
                "ticks": int(q.shape[0] * q.shape[1]),
                "figure": figure,
                "first_failure": result["first_failure"],
            }
        )
    return rows


def stability_scenarios(cache: Path, *, quick: bool) -> list[Scenario]:
    walk_steps = 10_000 if quick else 1_000_000
    fan_steps = 5_000 if quick else 100_000
    faces = 80 if quick else 320
    return [
        wall_scenario(),
        fan_scenario("edge shared by 12 tets", _core.edge_fan_mesh(12), fan_steps),
        fan_scenario("vertex shared by 20 tets", _core.icosahedron_mesh(10.0), fan_steps),
        sliver_scenario(fan_steps),
        exact_points_scenario(),
        sphere_stroke_scenario(cache, faces, 50.0),
        random_walk_scenario(cache, faces, walk_steps),
    ]


# ---- The closed loop with the simulated hand --------------------------------------------

HAND_MASS_KG = 0.1
HAND_DAMPING_N_S_PER_MM = 0.002  # 2 N s/m
HAND_STIFFNESS_N_PER_MM = 0.3  # The grip holding the tool toward the scripted target.
CLOSED_LOOP_K = (0.05, 0.1, 0.2, 0.5, 1.0, 2.0)
HAND_PRESS_MM = 5.0  # Depth of the scripted stroke's target into the sphere.
# Chatter: the held force swings by more than this share of its mean (and this much).
CHATTER_SHARE = 0.05
CHATTER_MIN_N = 0.01
# An active loop: the hand gains more than this share of the contact's stored energy.
ENERGY_SHARE = 0.01


def hand_target(dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """A stroke on the top of the sphere: approach, press 5 mm in (0.2 s), slide
    (0.5 s), hold (0.3 s), withdraw. Returns targets (ticks, 3) and a hold mask."""
    r = meshes.SPHERE_RADIUS_MM
    t = np.arange(0.0, 1.4, dt_s)
    u = np.array([0.3, 0.2, 1.0]) / np.linalg.norm([0.3, 0.2, 1.0])
    w = np.cross(u, [1.0, 0.0, 0.0])
    w /= np.linalg.norm(w)
    radius = np.interp(
        t,
        [0, 0.2, 0.9, 1.2, 1.4],
        [
            r + HAND_PRESS_MM,
            r - HAND_PRESS_MM,
            r - HAND_PRESS_MM,
            r - HAND_PRESS_MM,
            r + HAND_PRESS_MM,
        ],
    )
    angle = np.interp(t, [0, 0.2, 0.7, 1.4], [0, 0, 0.5, 0.5])
    target = radius[:, None] * (np.cos(angle)[:, None] * u + np.sin(angle)[:, None] * w)
    hold = (t > 1.0) & (t < 1.2)
    return target, hold


def closed_loop(method_set, target: np.ndarray, hold: np.ndarray, dt_s: float) -> dict:
    """Semi-implicit Euler of the hand: m a = k_h (target - x) - b v + f_rendered.
    Returns the work done on the hand by the rendered force (N mm = mJ; > 0 means
    the haptic loop gave energy to the hand) and the oscillation during the hold."""
    x = target[0].copy()
    v = np.zeros(3)
    method_set.reset(x[None])
    work = 0.0
    forces = np.zeros((len(target), 3))
    for k in range(len(target)):
        method_set.step(x[None], dt_s)
        f = method_set.force_N[0]
        total = f + HAND_STIFFNESS_N_PER_MM * (target[k] - x) - HAND_DAMPING_N_S_PER_MM * v
        v = v + total / HAND_MASS_KG * 1000.0 * dt_s  # N/kg = m/s^2 = 1000 mm/s^2
        x_next = x + v * dt_s
        work += float(f @ (x_next - x))
        x = x_next
        forces[k] = f
    held = np.linalg.norm(forces[hold], axis=1)
    ripple = float(held.max() - held.min()) if held.size else 0.0
    return {
        "energy_gained_mJ": work,
        "hold_force_N": float(held.mean()) if held.size else 0.0,
        "hold_ripple_N": ripple,
    }


def run_closed_loop(cache: Path, *, quick: bool, families=None) -> list[dict]:
    faces = 80 if quick else 320
    scene = meshes.sphere_in_cube(faces, cache)
    dt = 0.001
    target, hold = hand_target(dt)
    rows = []
    families = families or (methods.TET, methods.SHADED, methods.GOD, methods.VOXEL)
    for k in CLOSED_LOOP_K:
        space = scene.space(stiffness_N_per_mm=k)
        for method in methods.methods_for(
            scene,
            space,
            families=families,
            voxel_sizes=(1.0,),
            inside=sphere_inside,
            stiffness_N_per_mm=k,
        ):
            figures = closed_loop(method.make(1), target, hold, dt)
            # Chatter or a limit cycle: the force still swings by more than 5 %
            # of its mean (and 0.01 N) while the target is held still; an
            # active loop: the hand gained more than 1 % of the contact's
            # stored energy (0.5 k d^2 at the target depth d) over the stroke.
            stored = 0.5 * k * HAND_PRESS_MM**2
            chatter = figures["hold_ripple_N"] > max(
                CHATTER_MIN_N, CHATTER_SHARE * figures["hold_force_N"]
            )
            active = figures["energy_gained_mJ"] > ENERGY_SHARE * stored
            rows.append(
                {
                    "k_N_per_mm": k,
                    "method": method.label,
                    "family": method.family,
                    **figures,
                    "chatter": chatter,
                    "energy_flag": active,
                    "verdict": "FAIL" if chatter or active else "pass",
                }
            )
    return rows
