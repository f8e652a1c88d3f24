"""Accuracy where the truth is known: a sphere of radius 30 mm, pressed 5 mm in
and slid along at 100 mm/s, sampled at 1 kHz and 50 Hz (paths.press_and_slide)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from hapticut_evaluation import _baselines, meshes, methods, paths

SPHERE_FACES = (80, 320, 1280, 5120)
RATES_HZ = (1000.0, 50.0)
# Passes per method and round of timing: the first warms the caches.
WARM_PASSES = 3
# Each method keeps its best round of at least this long a series of rounds.
TIMING_MIN_S = 3.0


def sphere_inside(points: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", points, points) < meshes.SPHERE_RADIUS_MM**2


def contact_metrics(path: np.ndarray, mask: np.ndarray, q: np.ndarray, force: np.ndarray) -> dict:
    """Force-direction error against the true normal p/|p| (degrees), surface
    position error ||q| - R| and penetration max(R - |q|, 0) (mm), over `mask` ticks."""
    p, q, f = path[mask], q[mask], force[mask]
    normal = p / np.linalg.norm(p, axis=-1, keepdims=True)
    magnitude = np.linalg.norm(f, axis=-1)
    cosine = np.einsum("...i,...i", f, normal) / np.maximum(magnitude, 1e-300)
    angle = np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0))).ravel()
    radius = np.linalg.norm(q, axis=-1).ravel()
    r = meshes.SPHERE_RADIUS_MM
    return {
        "dir_err_mean_deg": float(angle.mean()),
        "dir_err_p95_deg": float(np.percentile(angle, 95)),
        "dir_err_max_deg": float(angle.max()),
        "pos_err_mean_mm": float(np.abs(radius - r).mean()),
        "pos_err_max_mm": float(np.abs(radius - r).max()),
        "penetration_max_mm": float(max(0.0, (r - radius).max())),
    }


def time_round_robin(
    method_sets, path: np.ndarray, dt_s: float, repeats: int, min_seconds: float = 0.0
) -> list[float]:
    """ns per point update of each method set along the path, with warm caches (as
    in a servo loop, where the hand stays near the same elements): the best of at
    least `repeats` rounds (more until `min_seconds` have passed), each round
    timing every method in turn for `WARM_PASSES` passes in a row. A slow spell of
    this shared machine (they last seconds) then slows all methods of a round
    alike, and the best round of each method is one outside the spells."""
    return time_round_robin_paths(
        method_sets, [path] * len(method_sets), dt_s, repeats, min_seconds
    )


def time_round_robin_paths(
    method_sets, paths: list[np.ndarray], dt_s: float, repeats: int, min_seconds: float = 0.0
) -> list[float]:
    """time_round_robin with a path of its own for each method set."""
    best = [float("inf")] * len(method_sets)
    start = time.perf_counter()
    rounds = 0
    while rounds < repeats or time.perf_counter() - start < min_seconds:
        for k, (method_set, path) in enumerate(zip(method_sets, paths, strict=True)):
            best[k] = min(best[k], method_set.time(path, dt_s, repeats=WARM_PASSES))
        rounds += 1
    return best


def run_accuracy(
    cache: Path,
    *,
    faces=SPHERE_FACES,
    voxel_sizes=methods.VOXEL_SIZES_MM,
    points: int = 8,
    repeats: int = 9,
    min_seconds: float = TIMING_MIN_S,
    log=print,
) -> list[dict]:
    """One row per (method, model size, rate)."""
    rows = []
    voxel_done = False
    for n_faces in faces:
        scene = meshes.sphere_in_cube(n_faces, cache)
        space = scene.space()
        # The voxel method does not depend on the sphere's facets: run it once,
        # voxelising the true sphere (its best case).
        sizes = () if voxel_done else voxel_sizes
        families = (methods.TET, methods.SHADED, methods.GOD) + ((methods.VOXEL,) if sizes else ())
        chosen = methods.methods_for(
            scene, space, families=families, voxel_sizes=sizes, inside=sphere_inside
        )
        for rate in RATES_HZ:
            path, slide = paths.press_and_slide(1.0 / rate, points=points)
            started = [methods.start(method.make(points), path) for method in chosen]
            best_ns = time_round_robin(started, path, 1.0 / rate, repeats, min_seconds)
            for method, method_set, ns in zip(chosen, started, best_ns, strict=True):
                result = method_set.run(path, 1.0 / rate, timing_repeats=0)
                metrics = contact_metrics(path, slide, result["q"], result["force_N"])
                is_voxel = method.family == methods.VOXEL
                row = {
                    "method": method.family,
                    "label": method.label,
                    "model": "true sphere" if is_voxel else f"{n_faces} faces",
                    "faces": 0 if is_voxel else n_faces,
                    "voxel_mm": float(method.label.split()[-2]) if is_voxel else 0.0,
                    "rate_Hz": rate,
                    "ns_per_update": ns,
                    "memory_bytes": method_set.memory_bytes,
                    "tets": 0 if is_voxel else space.tet_count,
                    **metrics,
                }
                rows.append(row)
                log(
                    f"  {row['label']:32s} {row['model']:12s} {rate:6.0f} Hz "
                    f"{ns:8.1f} ns  dir {metrics['dir_err_mean_deg']:6.3f} deg mean"
                )
        voxel_done = True
    return rows


def run_drag_lag(cache: Path, *, faces: int = 320, points: int = 8) -> list[dict]:
    """Lag |q - p| inside a drag sphere (D = 1 mm) during the slide, per rate: the
    tetrahedral proxy only (the baselines have no penetrable material)."""
    scene = meshes.sphere_in_cube(faces, cache)
    space = scene.space(material=meshes.DRAG)
    rows = []
    for rate in RATES_HZ:
        path, slide = paths.press_and_slide(1.0 / rate, points=points)
        result = methods.start(_baselines.TetMethodSet(space, points), path).run(path, 1.0 / rate)
        lag = np.linalg.norm(result["q"] - path, axis=-1)[slide]
        rows.append(
            {
                "method": methods.TET,
                "model": f"drag sphere, {faces} faces",
                "rate_Hz": rate,
                "drag_distance_mm": 1.0,
                "lag_mean_mm": float(lag.mean()),
                "lag_max_mm": float(lag.max()),
                "lag_min_mm": float(lag.min()),
            }
        )
    return rows
