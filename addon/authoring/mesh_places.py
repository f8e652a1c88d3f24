"""Where on an object a problem lies, said so the user can find it: a point in the object's own
units and in the world's millimetres, and the faces (their indices in the mesh with its
modifiers, what Edit Mode shows when there are none). The toolkit names the object and the
problem; only Blender has the object's own frame and face numbers, so the place is found
here, with Blender's own BVH tree, on the same evaluated mesh the build is given.

Also one check the toolkit's does not make: closed parts of one object that touch (two cubes
sharing an edge are each closed, so nothing else sees them).
"""

from __future__ import annotations

import numpy as np
from mathutils import Vector
from mathutils.bvhtree import BVHTree

from ..toolkit.units import mm_per_unit

# Above this many triangles the place is not looked for: the check would hold Blender's UI.
MAX_TRIANGLES = 1_000_000
# Faces named in a message; the count says how many more.
FACES_SHOWN = 6
# Parts closer than this share of the object's diagonal touch.
TOUCH_SHARE = 1e-5
# Above this many parts only parts sharing a vertex's place are found (one tree per part).
MAX_PARTS_NEAREST = 16


class Mesh:
    """An object's evaluated mesh in its own frame: vertices (n, 3), triangles (t, 3), the
    polygon of each triangle (t,)."""

    def __init__(self, obj, depsgraph) -> None:
        self.obj = obj
        evaluated = obj.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        try:
            mesh.calc_loop_triangles()
            self.vertices = np.empty((len(mesh.vertices), 3))
            mesh.vertices.foreach_get("co", self.vertices.ravel())
            self.triangles = np.empty((len(mesh.loop_triangles), 3), dtype=np.int64)
            mesh.loop_triangles.foreach_get("vertices", self.triangles.ravel())
            self.polygons = np.empty(len(mesh.loop_triangles), dtype=np.int64)
            mesh.loop_triangles.foreach_get("polygon_index", self.polygons)
        finally:
            evaluated.to_mesh_clear()
        self.world = evaluated.matrix_world.copy()

    def tree(self, triangles=None, world: bool = False) -> BVHTree:
        vertices = self.world_vertices() if world else self.vertices
        chosen = self.triangles if triangles is None else self.triangles[triangles]
        return BVHTree.FromPolygons(vertices.tolist(), chosen.tolist())

    def world_vertices(self) -> np.ndarray:
        matrix = np.array(self.world)
        return self.vertices @ matrix[:3, :3].T + matrix[:3, 3]

    def diagonal(self) -> float:
        if not len(self.vertices):
            return 0.0
        return float(np.linalg.norm(self.vertices.max(axis=0) - self.vertices.min(axis=0)))


def place_text(mesh: Mesh, scene, triangles: np.ndarray, points=None) -> str:
    """Where the given triangles are (or the points, when given: a hole's rim rather than
    the faces around it): the densest cluster's centre in the object's units and in world
    mm, and the triangles' faces."""
    if not len(triangles):
        return ""
    centres = mesh.vertices[mesh.triangles[triangles]].mean(axis=1) if points is None else points
    centre = _densest(centres, max(mesh.diagonal() * 0.05, 1e-12))
    world = mesh.world @ Vector(centre)
    mm = mm_per_unit(scene)
    faces = np.unique(mesh.polygons[triangles])
    shown = ", ".join(str(f) for f in faces[:FACES_SHOWN])
    more = f" and {len(faces) - FACES_SHOWN} more" if len(faces) > FACES_SHOWN else ""
    stack = " of the mesh with its modifiers" if len(mesh.obj.modifiers) else ""
    return (
        f"near ({_xyz(centre)}) in {mesh.obj.name}'s own units, ({_xyz(np.array(world) * mm)}) "
        f"mm in the world; faces {shown}{more}{stack}"
    )


def _xyz(point) -> str:
    return ", ".join(f"{c:.3g}" for c in point)


def _densest(points: np.ndarray, cell: float) -> np.ndarray:
    """The centre of the points in the fullest grid cell (several places: the worst one)."""
    keys = np.floor(points / cell).astype(np.int64)
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    return points[inverse.ravel() == np.argmax(counts)].mean(axis=0)


def self_crossing(mesh: Mesh) -> np.ndarray:
    """Triangles that cross another triangle of the same mesh."""
    tree = mesh.tree()
    pairs = np.array(tree.overlap(tree), dtype=np.int64).reshape(-1, 2)
    return np.unique(pairs)


def edge_faces(mesh: Mesh, uses_wanted) -> tuple[np.ndarray, np.ndarray]:
    """Triangles with an edge used by a number of triangles that uses_wanted accepts (1: a
    hole's rim; more than 2: a non-manifold edge), and those edges' midpoints."""
    tris = mesh.triangles
    edges = np.sort(tris[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, inverse, uses = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
    wanted = uses_wanted(uses)[inverse.ravel()]
    midpoints = mesh.vertices[edges[wanted]].mean(axis=1)
    return np.unique(np.nonzero(wanted)[0] // 3), midpoints


def crossing_other(mesh: Mesh, other: Mesh) -> np.ndarray:
    """Triangles of mesh that cross other's (both in world coordinates)."""
    pairs = mesh.tree(world=True).overlap(other.tree(world=True))
    return np.unique(np.array([a for a, _ in pairs], dtype=np.int64))


def nearest_to_other(mesh: Mesh, other: Mesh) -> np.ndarray:
    """The triangle of mesh nearest to other (world coordinates), as a one-element array."""
    tree = other.tree(world=True)
    world = mesh.world_vertices()
    best, best_vertex = float("inf"), 0
    step = max(1, len(world) // 20000)  # A sample: the place, not the distance.
    for index in range(0, len(world), step):
        hit = tree.find_nearest(Vector(world[index]))
        if hit[0] is not None and hit[3] < best:
            best, best_vertex = hit[3], index
    touching = np.nonzero((mesh.triangles == best_vertex).any(axis=1))[0]
    return touching[:1]


def parts(triangles: np.ndarray, vertex_count: int) -> np.ndarray:
    """The connected part of every vertex (linked through triangles), numbered from 0."""
    parent = np.arange(vertex_count)
    a = triangles.ravel()
    b = triangles[:, [1, 2, 0]].ravel()
    while True:
        low, high = np.minimum(parent[a], parent[b]), np.maximum(parent[a], parent[b])
        joined = low != high
        if not joined.any():
            break
        np.minimum.at(parent, high[joined], low[joined])
        while True:  # Every vertex straight to its part's smallest vertex.
            jumped = parent[parent]
            if (jumped == parent).all():
                break
            parent = jumped
    return np.unique(parent, return_inverse=True)[1].ravel()


def touching_parts(mesh: Mesh) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of parts that touch another part of the same mesh at a vertex, an edge or a
    face, and the vertices where they touch: a vertex of one at the same place as one of
    another (numpy, any number of parts), or on a face of another (Blender's BVH; up to
    MAX_PARTS_NEAREST parts)."""
    part = parts(mesh.triangles, len(mesh.vertices))
    tri_part = part[mesh.triangles[:, 0]]
    labels = np.unique(tri_part)
    if len(labels) < 2:
        return np.empty(0, dtype=np.int64), np.empty((0, 3))
    used = np.unique(mesh.triangles)
    tolerance = max(mesh.diagonal() * TOUCH_SHARE, 1e-12)
    keys = np.round(mesh.vertices[used] / tolerance).astype(np.int64)
    _, inverse = np.unique(keys, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    vertex_part = part[used]
    lowest = np.full(inverse.max() + 1, len(labels), dtype=np.int64)
    highest = np.full(inverse.max() + 1, -1, dtype=np.int64)
    np.minimum.at(lowest, inverse, vertex_part)
    np.maximum.at(highest, inverse, vertex_part)
    shared = lowest != highest  # Places holding vertices of two parts.
    touching_vertices = used[shared[inverse]].tolist()
    if not touching_vertices and len(labels) <= MAX_PARTS_NEAREST:
        for label in labels:
            others = np.nonzero(tri_part != label)[0]
            tree = mesh.tree(others)
            for vertex in used[part[used] == label]:
                if tree.find_nearest(Vector(mesh.vertices[vertex]), tolerance)[0] is not None:
                    touching_vertices.append(int(vertex))
    triangles = np.nonzero(np.isin(mesh.triangles, touching_vertices).any(axis=1))[0]
    return triangles, mesh.vertices[np.array(touching_vertices, dtype=np.int64)]
