"""The order a built scene stores its tets and vertices in: near in space, near in memory.

A proxy's walk visits tets that touch each other. fTetWild numbers tets in an
order where two neighbours are on median about 1500 places apart, so each new
tet of a walk is a cache miss in every array the engine keeps per tet (planes,
neighbours, material). Sorted along a Hilbert curve through their centroids,
neighbours are mostly a few places apart and share cache lines and pages; the
vertices follow, numbered by their first use. The order changes nothing of the
scene's geometry or materials (docs/decisions.md, "Tet order in a built scene").
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..scenefile.model import Scene

HILBERT_BITS = 16  # Per axis: 65536 cells along each side of the mesh's box.


def hilbert_keys(points: np.ndarray, bits: int = HILBERT_BITS) -> np.ndarray:
    """Each point's index along a 3D Hilbert curve through the points' box ((n,) int64).

    Skilling's transpose algorithm ("Programming the Hilbert curve", 2004),
    vectorised over the points: consecutive indices are neighbouring cells.
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if len(points) == 0:
        return np.zeros(0, np.int64)
    lo, hi = points.min(axis=0), points.max(axis=0)
    span = np.where(hi > lo, hi - lo, 1.0)
    cells = (1 << bits) - 1
    x = np.clip(np.rint((points - lo) / span * cells), 0, cells).astype(np.int64).T.copy()
    top = 1 << (bits - 1)
    # Inverse undo.
    q = top
    while q > 1:
        low = q - 1
        for i in range(3):
            hit = (x[i] & q) != 0
            x[0] = np.where(hit, x[0] ^ low, x[0])
            swap = np.where(hit, 0, (x[0] ^ x[i]) & low)
            x[0] ^= swap
            x[i] ^= swap
        q >>= 1
    # Gray encode.
    for i in range(1, 3):
        x[i] ^= x[i - 1]
    flip = np.zeros_like(x[0])
    q = top
    while q > 1:
        flip = np.where((x[2] & q) != 0, flip ^ (q - 1), flip)
        q >>= 1
    for i in range(3):
        x[i] ^= flip
    key = np.zeros(x.shape[1], np.int64)
    for b in range(bits - 1, -1, -1):
        for i in range(3):
            key = (key << 1) | ((x[i] >> b) & 1)
    return key


def locality_order(vertices: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(tet_order, vertex_order): the tets along a Hilbert curve through their centroids,
    the vertices by their first use in that order (unused vertices last, as they were).

    new_tets = new_index_of_vertex[tets[tet_order]], new_vertices = vertices[vertex_order].
    """
    vertices = np.asarray(vertices, dtype=np.float64)
    tets = np.asarray(tets, dtype=np.int64)
    tet_order = np.argsort(hilbert_keys(vertices[tets].mean(axis=1)), kind="stable")
    first_use = np.full(len(vertices), tets.size, np.int64)
    np.minimum.at(first_use, tets[tet_order].ravel(), np.arange(tets.size))
    vertex_order = np.argsort(first_use, kind="stable")
    return tet_order, vertex_order


def renumbered(
    vertices: np.ndarray,
    tets: np.ndarray,
    tet_materials: np.ndarray,
    tet_order: np.ndarray,
    vertex_order: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The mesh with tet tet_order[i] stored as tet i and vertex vertex_order[j] as vertex j:
    (vertices, tets int32, tet_materials int32)."""
    vertices = np.asarray(vertices, dtype=np.float64)
    new_index = np.empty(len(vertices), np.int64)
    new_index[vertex_order] = np.arange(len(vertices))
    return (
        vertices[vertex_order],
        new_index[np.asarray(tets)[tet_order]].astype(np.int32),
        np.asarray(tet_materials)[tet_order].astype(np.int32),
    )


def in_locality_order(
    vertices: np.ndarray, tets: np.ndarray, tet_materials: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The same mesh renumbered by locality_order: (vertices, tets int32, tet_materials int32)."""
    return renumbered(vertices, tets, tet_materials, *locality_order(vertices, tets))


def scene_in_locality_order(scene: Scene) -> Scene:
    """The scene with its mesh renumbered by locality_order (what ``hapticut build`` writes)."""
    vertices, tets, tet_materials = in_locality_order(
        scene.vertices, scene.tets, scene.tet_materials
    )
    return replace(scene, vertices=vertices, tets=tets, tet_materials=tet_materials)
