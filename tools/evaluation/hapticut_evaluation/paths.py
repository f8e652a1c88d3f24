"""Device paths of the evaluation, as (ticks, N, 3) arrays in mm."""

from __future__ import annotations

import numpy as np

from hapticut_evaluation.meshes import CUBE_HALF_MM, SPHERE_RADIUS_MM

SLIDE_SPEED_MM_S = 100.0
PRESS_DEPTH_MM = 5.0


def great_circle_frames(count: int, seed: int = 7) -> list[tuple[np.ndarray, np.ndarray]]:
    """`count` orthonormal pairs (start direction, slide direction), fixed by the seed,
    so the strokes cross facets, edges and vertices at no special angle."""
    rng = np.random.default_rng(seed)
    frames = []
    for _ in range(count):
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        w = rng.normal(size=3)
        w -= u * (w @ u)
        w /= np.linalg.norm(w)
        frames.append((u, w))
    return frames


def press_and_slide(
    dt_s: float,
    *,
    points: int = 8,
    radius_mm: float = SPHERE_RADIUS_MM,
    depth_mm: float = PRESS_DEPTH_MM,
    slide_s: float = 1.0,
    speed_mm_s: float = SLIDE_SPEED_MM_S,
) -> tuple[np.ndarray, np.ndarray]:
    """Start 5 mm outside the sphere, press `depth_mm` in along the normal, then slide
    along a great circle at `speed_mm_s` for `slide_s`; one stroke per point.
    Returns the path (ticks, points, 3) and a (ticks,) mask of the slide phase."""
    press_s = (5.0 + depth_mm) / speed_mm_s
    times = np.arange(0.0, press_s + slide_s + 1e-12, dt_s)
    path = np.zeros((len(times), points, 3))
    inner = radius_mm - depth_mm
    for i, (u, w) in enumerate(great_circle_frames(points)):
        r = np.where(times < press_s, radius_mm + 5.0 - speed_mm_s * times, inner)
        angle = np.where(times < press_s, 0.0, (times - press_s) * speed_mm_s / inner)
        path[:, i, :] = r[:, None] * (np.cos(angle)[:, None] * u + np.sin(angle)[:, None] * w)
    return np.ascontiguousarray(path), times >= press_s


def random_walk(
    steps: int,
    *,
    points: int = 1,
    step_mm: float = 1.0,
    seed: int = 3,
    half_mm: float = CUBE_HALF_MM - 1.0,
) -> np.ndarray:
    """Gaussian steps of `step_mm` per axis, reflected to stay in the cube."""
    rng = np.random.default_rng(seed)
    steps_xyz = rng.normal(scale=step_mm, size=(steps, points, 3))
    start = np.zeros((1, points, 3))
    start[0, :, 2] = half_mm - 1.0
    path = start + np.cumsum(steps_xyz, axis=0)
    # Reflect into [-half, half].
    period = 4.0 * half_mm
    path = np.mod(path + half_mm, period)
    path = np.where(path > 2 * half_mm, period - path, path) - half_mm
    return np.ascontiguousarray(path)
