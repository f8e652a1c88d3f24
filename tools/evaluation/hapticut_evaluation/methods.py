"""The methods under comparison, behind one interface (reset, step, run, force_N):
the tetrahedral proxy, the same with force shading, the surface god-object
with a bounding-volume tree, and the voxel proxy at several cell sizes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from hapticut import _core

from hapticut_evaluation import _baselines
from hapticut_evaluation.meshes import CUBE_HALF_MM, TetScene

TET = "tet proxy"
SHADED = "tet proxy + force shading"
GOD = "surface god-object (BVH)"
VOXEL = "voxel proxy"
VOXEL_SIZES_MM = (4.0, 2.0, 1.0, 0.5, 0.25)


@dataclass
class Method:
    """One method on one scene: `label` names it in tables (with the voxel size)."""

    family: str
    label: str
    make: object  # (count) -> a method set
    allowance_mm: float  # depth into the true rigid region that is not a fall-through


def voxel_grid(
    scene: TetScene, space: _core.Space, cell_mm: float, inside=None
) -> _baselines.VoxelGrid:
    """A grid over the cube [-45, 45]^3 mm (cells outside count as free). `inside`
    (points -> bool) voxelises an analytic solid; else the Space's rigid tets."""
    n = int(np.ceil(2 * CUBE_HALF_MM / cell_mm))
    origin = np.full(3, -CUBE_HALF_MM)
    if inside is None:
        return _baselines.VoxelGrid.from_space(space, origin, cell_mm, [n, n, n])
    centres = origin[0] + (np.arange(n) + 0.5) * cell_mm
    y, x = np.meshgrid(centres, centres, indexing="ij")
    solid = np.zeros((n, n, n), np.uint8)
    for k, z in enumerate(centres):
        points = np.stack([x.ravel(), y.ravel(), np.full(x.size, z)], axis=1)
        solid[k] = inside(points).reshape(n, n)
    return _baselines.VoxelGrid(origin, cell_mm, solid)


def methods_for(
    scene: TetScene,
    space: _core.Space,
    *,
    families=(TET, SHADED, GOD, VOXEL),
    voxel_sizes=VOXEL_SIZES_MM,
    inside=None,
    stiffness_N_per_mm: float = 0.1,
) -> list[Method]:
    """Every method on one scene. The god-object and force shading use the scene's
    source surface when it has one (what the scene was built from), else the
    rigid surface of the tet mesh."""
    if scene.surface_vertices is not None:
        sv, st = scene.surface_vertices, scene.surface_triangles
    else:
        sv, st = _baselines.rigid_surface(space)
    out = []
    exact = 100.0 * space.tolerance_mm
    # The god-object collides with the source surface, the depth is measured in
    # the tet mesh's rigid region: allow for how far that region bulges out of
    # the source (fTetWild keeps it within its envelope).
    source_gap = 0.0
    if scene.surface_vertices is not None:
        tv, _ = _baselines.rigid_surface(space)
        source_gap = _outside_distance(tv, sv, st)
    if TET in families:
        out.append(Method(TET, TET, lambda n: _baselines.TetMethodSet(space, n), exact))
    if SHADED in families:
        shading = _core.ForceShading(space, sv, st)
        out.append(
            Method(SHADED, SHADED, lambda n: _baselines.TetMethodSet(space, n, shading), exact)
        )
    if GOD in families and len(st) > 0:
        out.append(
            Method(
                GOD,
                GOD,
                lambda n: _baselines.GodObjectSet(sv, st, n, stiffness_N_per_mm=stiffness_N_per_mm),
                exact + source_gap,
            )
        )
    if VOXEL in families:
        for h in voxel_sizes:
            grid = voxel_grid(scene, space, h, inside)
            out.append(
                Method(
                    VOXEL,
                    f"{VOXEL} {h:g} mm",
                    lambda n, grid=grid: _baselines.VoxelProxySet(grid, n, stiffness_N_per_mm),
                    h * 3**0.5,
                )
            )
    return out


def _outside_distance(points: np.ndarray, vertices: np.ndarray, triangles: np.ndarray) -> float:
    """How far the points reach out of a convex closed surface (0 when all inside)."""
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n, axis=1)[:, None]
    d = np.einsum("ij,ij->i", n, a)
    return float(max(0.0, (points @ n.T - d).max(axis=1).max()))


def start(method_set, path: np.ndarray):
    method_set.reset(np.ascontiguousarray(path[0]))
    return method_set
