"""Closed surfaces made in code, for regions of test scenes and of the evaluation: the
geodesic sphere. (Enclosures and the Kuhn grid: hapticut.scenebuild.geometry; the engine's
reference tet meshes: hapticut._core.)"""

from __future__ import annotations

import numpy as np


def icosphere(
    radius_mm: float, subdivisions: int = 1, centre=(0.0, 0.0, 0.0)
) -> tuple[np.ndarray, np.ndarray]:
    """The icosahedron with each face split into 4^subdivisions triangles (20 x 4^n:
    80 faces at 1, 320 at 2), midpoints pushed onto the sphere of radius_mm around
    `centre`. Returns (vertices (v, 3), triangles (20 x 4^n, 3) int32), wound
    counter-clockwise seen from outside."""
    if not 0 <= subdivisions <= 6:
        raise ValueError(f"icosphere subdivisions must be 0 to 6, not {subdivisions}")
    t = (1.0 + 5.0**0.5) / 2.0
    verts = [
        (-1, t, 0),
        (1, t, 0),
        (-1, -t, 0),
        (1, -t, 0),
        (0, -1, t),
        (0, 1, t),
        (0, -1, -t),
        (0, 1, -t),
        (t, 0, -1),
        (t, 0, 1),
        (-t, 0, -1),
        (-t, 0, 1),
    ]
    tris = [
        (0, 11, 5),
        (0, 5, 1),
        (0, 1, 7),
        (0, 7, 10),
        (0, 10, 11),
        (1, 5, 9),
        (5, 11, 4),
        (11, 10, 2),
        (10, 7, 6),
        (7, 1, 8),
        (3, 9, 4),
        (3, 4, 2),
        (3, 2, 6),
        (3, 6, 8),
        (3, 8, 9),
        (4, 9, 5),
        (2, 4, 11),
        (6, 2, 10),
        (8, 6, 7),
        (9, 8, 1),
    ]
    points = [np.array(v, float) / np.linalg.norm(v) for v in verts]
    for _ in range(subdivisions):
        cache: dict[tuple[int, int], int] = {}

        def middle(a: int, b: int, cache=cache) -> int:
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = points[a] + points[b]
                points.append(m / np.linalg.norm(m))
                cache[key] = len(points) - 1
            return cache[key]

        new = []
        for a, b, c in tris:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        tris = new
    vertices = np.array(points) * radius_mm
    if np.any(centre):
        vertices = vertices + np.asarray(centre, dtype=np.float64)
    triangles = np.array(tris, np.int32)
    # Wind outward.
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    outward = a - np.asarray(centre, dtype=np.float64)
    flip = np.einsum("ij,ij->i", np.cross(b - a, c - a), outward) < 0
    triangles[flip] = triangles[flip][:, [0, 2, 1]]
    return vertices, triangles
