"""Small geometry functions on numpy arrays for scene building (no pymeshlab, no fTetWild).

Shapes: vertices (n, 3) float64 in mm; faces (f, 3) int triangles; tets (m, 4) int.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

# The four faces of a tet, each opposite the vertex of the same index, ordered so that for a
# positively oriented tet (signed volume > 0) every face's normal (right-hand rule) points out.
TET_FACES = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])
TET_EDGES = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])
# Work per chunk of winding-number evaluation: points x triangles (~30 MB per array).
_WINDING_CHUNK = 250_000


@dataclass
class Surface:
    """A closed, outward-oriented triangle surface: vertices (n, 3) float64, faces (f, 3) int32.

    The one triangle-surface type of the product (regions, the enclosure, meshed interfaces).
    """

    vertices: np.ndarray
    faces: np.ndarray


def signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Volume enclosed by a closed triangle surface; positive when its normals point out."""
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def triangle_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(f,) area of each triangle."""
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def tet_signed_volumes(vertices: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """(m,) signed volume of each tet (positive: vertex 3 on the left of face 0-1-2's normal)."""
    a, b, c, d = (vertices[tets[:, i]] for i in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0


def orient_tets(vertices: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """The tets with the last two vertices swapped where needed so every volume is positive."""
    tets = np.array(tets, dtype=np.int32, copy=True)
    negative = tet_signed_volumes(vertices, tets) < 0
    tets[negative, 2], tets[negative, 3] = tets[negative, 3], tets[negative, 2].copy()
    return tets


def winding_numbers(
    points: np.ndarray,
    vertices: np.ndarray,
    faces: np.ndarray,
    on_chunk: Callable[[float], None] | None = None,
) -> np.ndarray:
    """(n,) generalized winding number of a triangle surface at each point.

    The sum of the triangles' signed solid angles over 4 pi (Van Oosterom and Strackee's
    formula): about 1 inside a closed, outward-oriented surface, 0 outside, and smooth in
    between for surfaces with small holes or overlaps (Jacobson et al. 2013). Points outside
    the surface's bounding box get 0 (exact for closed surfaces).
    on_chunk(fraction done) is called after each chunk (a cancel raises from it).
    """
    points = np.asarray(points, dtype=np.float64)
    vertices = np.asarray(vertices, dtype=np.float64)
    faces = np.asarray(faces)
    out = np.zeros(len(points))
    if len(faces) == 0:
        return out
    # Outside the surface's bounding box a closed surface winds 0 times: skip those points.
    used = vertices[faces.ravel()]
    low, high = used.min(axis=0), used.max(axis=0)
    near = np.flatnonzero(np.all((points >= low) & (points <= high), axis=1))
    # Corner coordinates as contiguous rows: (3 corners, 3 axes, f).
    corner = np.ascontiguousarray(vertices[faces].transpose(1, 2, 0))
    step = max(1, _WINDING_CHUNK // len(faces))
    for start in range(0, len(near), step):
        rows = near[start : start + step]
        px, py, pz = (points[rows, i, None] for i in range(3))
        ax, ay, az = corner[0, 0] - px, corner[0, 1] - py, corner[0, 2] - pz
        bx, by, bz = corner[1, 0] - px, corner[1, 1] - py, corner[1, 2] - pz
        cx, cy, cz = corner[2, 0] - px, corner[2, 1] - py, corner[2, 2] - pz
        la = np.sqrt(ax * ax + ay * ay + az * az)
        lb = np.sqrt(bx * bx + by * by + bz * bz)
        lc = np.sqrt(cx * cx + cy * cy + cz * cz)
        numerator = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        denominator = (
            la * lb * lc
            + (ax * bx + ay * by + az * bz) * lc
            + (bx * cx + by * cy + bz * cz) * la
            + (cx * ax + cy * ay + cz * az) * lb
        )
        out[rows] = np.arctan2(numerator, denominator).sum(axis=1) / (2 * np.pi)
        if on_chunk is not None:
            on_chunk(min(1.0, (start + step) / len(near)))
    return out


def tet_face_keys(tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All 4m tet faces: (4m, 3) sorted vertex triples and (4m,) owning tet index.

    Face j of tet t is row j * m + t.
    """
    faces = np.concatenate([tets[:, TET_FACES[j]] for j in range(4)])
    owners = np.tile(np.arange(len(tets)), 4)
    return np.sort(faces, axis=1), owners


def face_pairs(tets: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Interior faces as tet pairs, and boundary faces.

    Returns (pairs (k, 2) tets sharing a face, pair_faces (k, 3) sorted vertex triples,
    boundary (b,) rows into the (4m,) face list of tet_face_keys).
    """
    keys, owners = tet_face_keys(tets)
    order = np.lexsort(keys.T[::-1])
    sorted_keys = keys[order]
    same = np.all(sorted_keys[1:] == sorted_keys[:-1], axis=1)
    first = np.flatnonzero(same)
    pairs = np.stack([owners[order[first]], owners[order[first + 1]]], axis=1)
    in_pair = np.zeros(len(keys), dtype=bool)
    in_pair[first] = True
    in_pair[first + 1] = True
    return pairs, sorted_keys[first], order[~in_pair]


def boundary_faces(tets: np.ndarray) -> np.ndarray:
    """(b, 3) boundary triangles of a tet mesh, oriented outward for positive tets."""
    faces = np.concatenate([tets[:, TET_FACES[j]] for j in range(4)])
    _, _, boundary = face_pairs(tets)
    return faces[boundary]


def interface_faces(tets: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """(k, 3) faces between a tet set and the rest (or the mesh boundary), oriented outward.

    inside: (m,) bool. For positive tets the triangles' normals point out of the set.
    """
    oriented = np.concatenate([tets[:, TET_FACES[j]] for j in range(4)])
    owners = np.tile(np.arange(len(tets)), 4)
    keys = np.sort(oriented, axis=1)
    order = np.lexsort(keys.T[::-1])
    sorted_keys = keys[order]
    same_next = np.zeros(len(keys), dtype=bool)
    same_next[:-1] = np.all(sorted_keys[1:] == sorted_keys[:-1], axis=1)
    same_prev = np.zeros(len(keys), dtype=bool)
    same_prev[1:] = same_next[:-1]
    partner = np.full(len(keys), -1)
    partner[same_next] = np.flatnonzero(same_next) + 1
    partner[same_prev] = np.flatnonzero(same_prev) - 1
    own_inside = inside[owners[order]]
    other_inside = np.where(partner >= 0, inside[owners[order[np.maximum(partner, 0)]]], False)
    keep = own_inside & ~other_inside
    return oriented[order[keep]]


def enclosure_surface(kind: str, low: np.ndarray, high: np.ndarray, margin_mm: float):
    """The closed, outward-oriented surface of an enclosure around the box [low, high].

    kind "box": the box grown by margin_mm on every side (12 triangles); "cube": the smallest
    cube with the same centre holding that box (12 triangles); "tetrahedron": the regular
    tetrahedron whose inscribed sphere holds the grown box's circumscribed sphere (4 triangles,
    the paper's suggestion: 4 boundary faces to test from OUTSIDE).
    Returns (vertices (n, 3), faces (f, 3)).
    """
    low = np.asarray(low, dtype=np.float64) - margin_mm
    high = np.asarray(high, dtype=np.float64) + margin_mm
    centre = (low + high) / 2
    if kind == "tetrahedron":
        in_radius = float(np.linalg.norm(high - low)) / 2
        # A regular tetrahedron's vertices lie at 3x its inradius from the centre.
        directions = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]) / np.sqrt(3)
        vertices = centre + 3 * in_radius * directions
        faces = np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]])
        if signed_volume(vertices, faces) < 0:
            faces = faces[:, ::-1]
        return vertices, faces
    if kind == "cube":
        half = float((high - low).max()) / 2
        low, high = centre - half, centre + half
    elif kind != "box":
        raise ValueError(f"unknown enclosure {kind!r} (expected 'box', 'cube' or 'tetrahedron')")
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    vertices = low + corners * (high - low)
    # Two triangles per side, outward (vertex index = 4x + 2y + z).
    faces = np.array(
        [
            [0, 1, 3], [0, 3, 2],  # x = low
            [4, 6, 7], [4, 7, 5],  # x = high
            [0, 4, 5], [0, 5, 1],  # y = low
            [2, 3, 7], [2, 7, 6],  # y = high
            [0, 2, 6], [0, 6, 4],  # z = low
            [1, 5, 7], [1, 7, 3],  # z = high
        ]
    )  # fmt: skip
    return vertices, faces


def enclosure_planes(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit outward normals (p, 3) and offsets (p,) of an enclosure's distinct face planes."""
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    normals = np.cross(b - a, c - a)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    offsets = np.einsum("ij,ij->i", normals, a)
    planes = np.unique(np.round(np.column_stack([normals, offsets]), 9), axis=0)
    return planes[:, :3], planes[:, 3]


def kuhn_grid(low: np.ndarray, high: np.ndarray, cells: tuple[int, int, int]):
    """A box split into cells, 6 positive tets per cell around its main diagonal (conforming):
    the engine's reference grid (``hapticut._core.grid_mesh``, ``reference_meshes.cpp``).

    Returns (vertices ((nx+1)(ny+1)(nz+1), 3), tets (6 nx ny nz, 4) int32).
    """
    from hapticut import _core

    axes = [np.linspace(low[i], high[i], n + 1).tolist() for i, n in enumerate(cells)]
    vertices, tets = _core.grid_mesh(*axes)
    return np.asarray(vertices, dtype=np.float64), np.asarray(tets, dtype=np.int32)


def point_segment_distance(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """(n,) distance from each point to the segment [start, end]."""
    start = np.asarray(start, dtype=np.float64)
    axis = np.asarray(end, dtype=np.float64) - start
    length2 = float(axis @ axis)
    t = np.zeros(len(points)) if length2 == 0 else np.clip((points - start) @ axis / length2, 0, 1)
    return np.linalg.norm(points - (start + t[:, None] * axis), axis=1)


def face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(f, 3) unit normal of each triangle (right-hand rule; zero for a degenerate one)."""
    a, b, c = (vertices[faces[:, i]] for i in range(3))
    normals = np.cross(b - a, c - a)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return normals / np.where(length > 0, length, 1.0)


# Work per chunk of ray casting: rays x triangles.
_RAY_CHUNK = 200_000


def ray_hit_distances(
    origins: np.ndarray, directions: np.ndarray, vertices: np.ndarray, faces: np.ndarray
) -> np.ndarray:
    """(n,) distance along each unit direction from its origin to the nearest triangle it
    crosses, inf where it crosses none (Moeller-Trumbore). Hits closer than a millionth of
    the surface's size are ignored: a ray leaving a surface point does not hit its own face."""
    origins = np.asarray(origins, dtype=np.float64)
    directions = np.asarray(directions, dtype=np.float64)
    out = np.full(len(origins), np.inf)
    if len(origins) == 0 or len(faces) == 0:
        return out
    a = vertices[faces[:, 0]]
    ab, ac = vertices[faces[:, 1]] - a, vertices[faces[:, 2]] - a
    near = 1e-6 * float(np.ptp(vertices, axis=0).max())
    step = max(1, _RAY_CHUNK // len(faces))
    for start in range(0, len(origins), step):
        o, d = origins[start : start + step, None], directions[start : start + step, None]
        p = np.cross(d, ac)  # (k, f, 3)
        det = np.einsum("kfi,fi->kf", p, ab)
        usable = np.abs(det) > 1e-12
        inv = np.where(usable, 1.0 / np.where(usable, det, 1.0), 0.0)
        s = o - a
        u = np.einsum("kfi,kfi->kf", s, p) * inv
        q = np.cross(s, ab)
        v = np.einsum("kfi,kfi->kf", np.broadcast_to(d, q.shape), q) * inv
        t = np.einsum("kfi,fi->kf", q, ac) * inv
        hit = usable & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > near)
        out[start : start + step] = np.where(hit, t, np.inf).min(axis=1)
    return out


def buried_faces(vertices: np.ndarray, faces: np.ndarray, probe_mm: float) -> np.ndarray:
    """(f,) bool: faces of a surface that crosses itself lying inside its own volume (the
    winding number is over a half on both sides of the face's centre, probe_mm away). They
    are no part of the solid's boundary, so no tet mesh of the solid can follow them."""
    centres = vertices[faces].mean(axis=1)
    normals = face_normals(vertices, faces)
    both = np.concatenate([centres + probe_mm * normals, centres - probe_mm * normals])
    winding = winding_numbers(both, vertices, faces)
    return (winding[: len(faces)] > 0.5) & (winding[len(faces) :] > 0.5)
