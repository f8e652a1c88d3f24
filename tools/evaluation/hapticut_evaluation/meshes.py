"""Meshes of the evaluation: icospheres in a cube (fTetWild), thin walls and
the paper's fans (reference meshes), cached as .npz inside the output folder."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from hapticut import _core, shapes
from hapticut.scenebuild import tetwild
from hapticut.scenebuild.geometry import enclosure_surface

SPHERE_RADIUS_MM = 30.0
CUBE_HALF_MM = 45.0
# Target tet edge of the sphere scenes: no finer than the scene needs. fTetWild
# refines wherever the sphere's facets require it (their edges are 2 to 16 mm),
# so a coarse target keeps the surface exact and the air and bone coarse (at 6
# mm the 80-face scene had 40k tets and 16 MB, at 16 mm about 2.5k and 1.1 MB).
SPHERE_EDGE_MM = 16.0
# Materials shared by every scene of the evaluation: 0 air, 1 drag (1 mm), 2 rigid.
MATERIALS = [
    {"name": "air", "model": "free"},
    {"name": "flesh", "model": "drag", "drag_distance_mm": 1.0},
    {"name": "bone", "model": "rigid"},
]
AIR, DRAG, RIGID = 0, 1, 2


@dataclass
class TetScene:
    """A labelled tet mesh, and the exact surface of its solid when there is one."""

    name: str
    vertices: np.ndarray
    tets: np.ndarray
    labels: np.ndarray
    build_s: float = 0.0
    surface_vertices: np.ndarray | None = None
    surface_triangles: np.ndarray | None = None

    def space(self, material: int | None = None, stiffness_N_per_mm: float = 0.1) -> _core.Space:
        """The Space, with every non-air tet given `material` when set."""
        labels = self.labels
        if material is not None:
            labels = np.where(labels != AIR, material, AIR).astype(np.int32)
        return _core.Space(
            self.vertices,
            self.tets,
            np.ascontiguousarray(labels, np.int32),
            MATERIALS,
            stiffness_N_per_mm=stiffness_N_per_mm,
        )


def icosphere(faces: int, radius_mm: float = SPHERE_RADIUS_MM) -> tuple[np.ndarray, np.ndarray]:
    """hapticut.shapes.icosphere by face count (80, 320, 1280, 5120: 20 x 4^n)."""
    levels = {20: 0, 80: 1, 320: 2, 1280: 3, 5120: 4, 20480: 5}
    if faces not in levels:
        raise ValueError(f"an icosphere has 20 x 4^n faces, not {faces}")
    return shapes.icosphere(radius_mm, levels[faces])


def cube_surface(half_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """The 12 outward triangles of the cube [-half_mm, half_mm]^3 (the builder's enclosure)."""
    vertices, faces = enclosure_surface("cube", np.full(3, -half_mm), np.full(3, half_mm), 0.0)
    return vertices, faces.astype(np.int32)


def tetrahedralize(
    vertices: np.ndarray,
    triangles: np.ndarray,
    *,
    edge_length_mm: float,
    epsilon: float = 2e-4,
    bg: tuple | None = None,
    threads: int = 2,
) -> tuple[np.ndarray, np.ndarray]:
    """fTetWild on a surface (the union of closed shells); returns vertices and tets.
    bg = (vertices, tets, edge lengths) gives a sizing field (adaptive sizing)."""
    params = tetwild.TetWildParams(
        edge_length_mm=float(edge_length_mm),
        envelope_mm=0.0,  # Not used: the envelope is given relative, as fTetWild takes it.
        simplify=False,
        threads=threads,
        envelope_relative=float(epsilon),
    )
    out_v, out_t = tetwild.tetrahedralize(vertices, triangles, params, bg)
    return np.ascontiguousarray(out_v, np.float64), np.ascontiguousarray(out_t, np.int32)


def inside_convex(points: np.ndarray, vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Which points lie inside a convex closed surface wound outward."""
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1)[:, None]
    d = np.einsum("ij,ij->i", n, a)
    return np.all(points @ n.T - d < 0, axis=1)


def sphere_in_cube(
    faces: int,
    cache: Path | None,
    *,
    edge_length_mm: float = SPHERE_EDGE_MM,
    bg: tuple | None = None,
    tag: str = "",
) -> TetScene:
    """The paper's set-up: an icosphere of radius 30 mm (rigid by default) in a
    tetrahedralized cube of air. Cached under `cache` (fTetWild varies by run)."""
    sv, st = icosphere(faces)
    name = f"sphere{faces}_e{edge_length_mm:g}{tag}"
    file = cache / f"{name}.npz" if cache is not None else None
    if file is not None and file.exists():
        data = np.load(file)
        return TetScene(
            name, data["vertices"], data["tets"], data["labels"], float(data["build_s"]), sv, st
        )
    cv, ct = cube_surface(CUBE_HALF_MM)
    vertices = np.vstack([sv, cv])
    triangles = np.vstack([st, ct + len(sv)])
    start = time.perf_counter()
    tv, tt = tetrahedralize(vertices, triangles, edge_length_mm=edge_length_mm, bg=bg)
    build_s = time.perf_counter() - start
    centroids = tv[tt].mean(axis=1)
    labels = np.where(inside_convex(centroids, sv, st), RIGID, AIR).astype(np.int32)
    if file is not None:
        file.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(file, vertices=tv, tets=tt, labels=labels, build_s=build_s)
    return TetScene(name, tv, tt, labels, build_s, sv, st)


def grid_scene(name: str, xs, ys, zs, solid_box, *, jitter: float = 0.0, seed: int = 1) -> TetScene:
    """A Kuhn-grid box (reference mesh) whose tets with centroid inside the
    axis-aligned solid_box ((lo), (hi)) are rigid."""
    v, t = _core.grid_mesh(list(xs), list(ys), list(zs), jitter, seed)
    c = v[t].mean(axis=1)
    lo, hi = (np.asarray(x, float) for x in solid_box)
    inside = np.all((c > lo) & (c < hi), axis=1)
    labels = np.where(inside, RIGID, AIR).astype(np.int32)
    return TetScene(name, v, t, labels)


def fan_scene(name: str, mesh: tuple[np.ndarray, np.ndarray]) -> TetScene:
    """The paper's fan set-ups with every other tet rigid: the centre edge or
    vertex touches rigid and free material alternately."""
    v, t = mesh
    labels = np.where(np.arange(len(t)) % 2 == 0, RIGID, AIR).astype(np.int32)
    return TetScene(name, np.asarray(v, float), np.asarray(t, np.int32), labels)


def env_threads() -> int:
    return max(1, min(2, os.cpu_count() or 1))
