"""The cut surface as a slit: two sheets, each offset from the swept surface along its
normals, facing away from each other. The swept surface lies in the blade's own plane, so a
single sheet renders in the same depth as the blade's faces wherever the blade still covers
it (they flicker against each other, or it hides behind them); the slit's sheets lie on
either side of the blade, as the two walls of a real cut do. No bpy.
"""

from __future__ import annotations

import numpy as np

# Faces around a vertex whose planes lie within this angle of a face's (either way round)
# shade smoothly into it: the swept surface bends gently where the blade turned, while a
# fold back over itself is a crease.
CREASE_DEG = 30.0
# The half-width of the slit beyond the blade's own half-thickness, as a share of the
# diagonal of the scene's material: depth buffers and ray offsets resolve it at any zoom a
# render uses, and on a 100 mm scene it is 0.1 mm, thinner than any knife's cut.
SLIT_SHARE = 0.001


def half_thickness(vertices: np.ndarray) -> float:
    """Half the extent of vertices (n, 3) across their flattest direction: a blade's
    half-thickness (0 for a flat blade)."""
    points = np.asarray(vertices, np.float64)
    if len(points) < 4:
        return 0.0
    centred = points - points.mean(axis=0)
    flattest = np.linalg.svd(centred, full_matrices=False)[2][-1]
    across = centred @ flattest
    return float(across.max() - across.min()) / 2.0


def slit(
    vertices: np.ndarray, faces: np.ndarray, face_frames: np.ndarray, offset: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The surface (vertices (n, 3), faces (f, 3), a frame per face) as two sheets, each face
    moved by +offset and -offset along its own normal: vertices (6f, 3) (the front sheet's
    corners, then the back sheet's in the same order), faces (2f, 3), frames (2f,). The back
    sheet's faces are reversed, so each face of a sheet faces away from its twin.

    Each face moves along its own normal, not its vertices' average: the swept surface is
    not consistently oriented (a stroke down, then across, sweeps faces wound both ways),
    and averaged normals cancel there and fold faces over. The faces of a sheet so part by
    offset x their angle, a hair at the slit's width."""
    vertices = np.asarray(vertices, np.float64).reshape(-1, 3)
    faces = np.asarray(faces, np.int64).reshape(-1, 3)
    corners = vertices[faces]
    crossed = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    lengths = np.linalg.norm(crossed, axis=1, keepdims=True)
    normals = np.divide(crossed, lengths, out=np.zeros_like(crossed), where=lengths > 0)
    moved = normals[:, None, :] * offset
    sheets = np.vstack([(corners + moved).reshape(-1, 3), (corners - moved).reshape(-1, 3)])
    front = np.arange(3 * len(faces)).reshape(-1, 3)
    back = front[:, ::-1] + 3 * len(faces)
    frames = np.asarray(face_frames)
    return sheets, np.vstack([front, back]), np.concatenate([frames, frames])


def slit_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The normal at each corner of slit()'s faces for smooth shading: (2f, 3, 3), the front
    sheet's faces then the back sheet's, each corner in its face's order.

    Each sheet's faces are apart (slit moves each along its own normal), so a renderer would
    shade each flat, and the swept surface's long thin triangles, a few degrees apart where
    the blade turned, would show as streaks in its highlights. A corner's normal is the
    area-weighted mean of the normals of the faces around its vertex in the swept surface
    within CREASE_DEG of its own face's plane, each turned to its own face's side (the
    surface is wound both ways where the sweep turned back)."""
    vertices = np.asarray(vertices, np.float64).reshape(-1, 3)
    faces = np.asarray(faces, np.int64).reshape(-1, 3)
    corners = vertices[faces]
    crossed = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    twice_area = np.linalg.norm(crossed, axis=1)
    own = np.divide(crossed, twice_area[:, None], out=np.zeros_like(crossed),
                    where=twice_area[:, None] > 0)  # fmt: skip
    corner_vertex = faces.ravel()
    corner_face = np.repeat(np.arange(len(faces)), 3)
    # Every (corner, face around the corner's vertex) pair, from the corners sorted by vertex.
    by_vertex = np.argsort(corner_vertex, kind="stable")
    uses = np.bincount(corner_vertex, minlength=len(vertices))
    first_use = np.concatenate([[0], np.cumsum(uses)[:-1]])
    around = uses[corner_vertex]
    pair_corner = np.repeat(np.arange(len(corner_vertex)), around)
    within = np.arange(len(pair_corner)) - np.repeat(np.cumsum(around) - around, around)
    pair_face = corner_face[by_vertex[np.repeat(first_use[corner_vertex], around) + within]]
    cosine = np.einsum("ij,ij->i", own[corner_face[pair_corner]], own[pair_face])
    near = np.abs(cosine) >= np.cos(np.radians(CREASE_DEG))
    weighted = (twice_area[pair_face] * np.sign(cosine))[:, None] * own[pair_face]
    summed = np.zeros((len(corner_vertex), 3))
    np.add.at(summed, pair_corner[near], weighted[near])
    length = np.linalg.norm(summed, axis=1, keepdims=True)
    front = np.where(length > 0, summed / np.where(length > 0, length, 1), own[corner_face])
    front = front.reshape(-1, 3, 3)
    return np.concatenate([front, -front[:, ::-1]])
