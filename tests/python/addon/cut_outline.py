"""How far a cut surface's outline lies from the outline of the edge's swept path within the
cuttable material (numpy only): the measure of the baked cut's outline.

The swept path is the ruled surface between consecutive rows of the edge's points (the cut
surface's rows). It is sampled about 0.1 mm apart; a sample lies *off* the cut when it is outside
cuttable material, in a quad the cut surface leaves out by its states, or on the sweep's own
border (the first and last rows, the edge's two ends). An outline vertex of a cut surface
that follows the path has an off sample within the sampling step; one left inside by a step
of whole tets or quads lies as far from them as the step is deep.
"""

from __future__ import annotations

import numpy as np


def weld(points: np.ndarray, tolerance: float = 0.01) -> np.ndarray:
    """A label per point, shared by points within about tolerance (mm) of each other: a baked
    mesh's corners are float32 and each slit face is moved on its own, so one vertex of the
    swept surface comes back as copies a rounding apart; and a crack narrower than a tenth of
    the sampling step (a crossing placed a hair inside either side of a row) is no outline at
    the measure's resolution. Two grids half a cell apart, so no pair is split by a cell's
    border in both."""
    points = np.asarray(points, np.float64)
    groups = [
        np.unique(np.floor(points / tolerance + shift), axis=0, return_inverse=True)[1].reshape(-1)
        for shift in (0.0, 0.5)
    ]
    labels = np.arange(len(points))
    while True:
        before = labels.copy()
        for group in groups:
            least = np.full(group.max() + 1, len(points))
            np.minimum.at(least, group, labels)
            labels = least[group]
        if np.array_equal(labels, before):
            return labels


def outline_points(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The vertices on the surface's outline (on an edge of one face only), welded first (a
    slit's or a clipped sheet's faces need not share vertices)."""
    vertices = np.asarray(vertices, np.float64)
    labels = weld(vertices)
    faces = labels[np.asarray(faces, np.int64)]
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), 1)
    edges = edges[edges[:, 0] != edges[:, 1]]  # A face of no area has no outline of its own.
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    return vertices[np.unique(unique[counts == 1])]


def off_samples(rows_q: np.ndarray, quad_ok: np.ndarray, cuttable, step_mm: float = 0.1):
    """Samples of the swept path about step_mm apart that are off the cut (module doc):
    (k, 3). ``rows_q`` (R, N, 3) the edge's points at the rows, ``quad_ok`` (R-1, N-1) the
    quads the states allow, ``cuttable(points) -> bool array``."""
    rows_q = np.asarray(rows_q, np.float64)
    spacing = np.linalg.norm(np.diff(rows_q, axis=1), axis=-1).max()
    per_point = max(1, int(np.ceil(spacing / step_mm)))
    u = (np.arange(per_point) / per_point)[None, :, None]
    off = []
    for r in range(len(rows_q) - 1):
        a, b = rows_q[r, :-1], rows_q[r, 1:]
        d, c = rows_q[r + 1, :-1], rows_q[r + 1, 1:]
        per_row = max(1, int(np.ceil(np.linalg.norm(d - a, axis=-1).max() / step_mm)))
        v = (np.arange(per_row) / per_row)[:, None, None]
        # (quads, per_row, per_point, 3): bilinear in each quad.
        grid = ((1 - v) * ((1 - u) * a[:, None, None] + u * b[:, None, None])
                + v * ((1 - u) * d[:, None, None] + u * c[:, None, None]))  # fmt: skip
        inside = cuttable(grid.reshape(-1, 3)).reshape(grid.shape[:-1])
        inside &= np.asarray(quad_ok[r], bool)[:, None, None]
        off.append(grid[~inside])
    border = np.concatenate([rows_q[0], rows_q[-1], rows_q[:, 0], rows_q[:, -1]])
    return np.concatenate([*off, border])


def path_rows(q: np.ndarray, step_mm: float = 0.1) -> np.ndarray:
    """Ticks of the recording's points q (T, N, 3), from the first, at which a point has
    gone step_mm or more since the last tick taken, and the last: the edge's path at about
    the sampling step, whatever rows a cut surface took."""
    taken, last = [0], q[0]
    for k in range(1, len(q)):
        if np.linalg.norm(q[k] - last, axis=-1).max() >= step_mm:
            taken.append(k)
            last = q[k]
    return np.unique(np.array([*taken, len(q) - 1]))


def allowed_quads(states: np.ndarray, rows: np.ndarray, state_tet: int = 0) -> np.ndarray:
    """(R-1, N-1): the quads whose two points stayed in tets (state TET) at every tick between
    the rows, as the cut surface allows them."""
    left = np.concatenate(
        [np.zeros((1, states.shape[1]), np.int64), np.cumsum(states != state_tet, 0)]
    )
    stayed = (left[rows[1:] + 1] - left[rows[:-1]]) == 0
    return stayed[:, :-1] & stayed[:, 1:]


def nearest_distances(points: np.ndarray, targets: np.ndarray, chunk: int = 256) -> np.ndarray:
    """The distance from each point to its nearest target."""
    out = np.empty(len(points))
    for begin in range(0, len(points), chunk):
        part = points[begin : begin + chunk]
        squared = ((part[:, None, :] - targets[None, :, :]) ** 2).sum(-1)
        out[begin : begin + chunk] = np.sqrt(squared.min(axis=1))
    return out


# How far round an outline vertex the material's boundary is looked for (mm): from well
# above where a cut places its crossings to half the sampling step.
PROBE_RADII_MM = (0.002, 0.005, 0.01, 0.02, 0.05)


def boundary_distance(points: np.ndarray, cuttable) -> np.ndarray:
    """For each point, the least of PROBE_RADII_MM at which one of 26 probes round it (the
    cube's faces, edges and corners) is out of the cuttable material; inf where none is. The
    path may dip out of the material for less than the sampling step (the chord between two
    points resting on a round bone): the surface's outline there is on the material's
    boundary, which the samples miss."""
    points = np.asarray(points, np.float64)
    steps = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)])
    steps = steps[np.any(steps != 0, axis=1)]
    directions = steps / np.linalg.norm(steps, axis=1, keepdims=True)
    found = np.full(len(points), np.inf)
    for radius in sorted(PROBE_RADII_MM, reverse=True):
        probes = (points[:, None, :] + radius * directions[None]).reshape(-1, 3)
        out = ~np.asarray(cuttable(probes), bool).reshape(len(points), -1).all(axis=1)
        found[out] = radius
    return found


def outline_deviation(vertices, faces, rows_q, quad_ok, cuttable) -> np.ndarray:
    """The distance (mm) from each outline vertex of the surface to the nearest point off the
    cut: 0 for an outline on the path's outline, the depth of a step for a stepped one."""
    outline = outline_points(vertices, faces)
    sampled = nearest_distances(outline, off_samples(rows_q, quad_ok, cuttable))
    return np.minimum(sampled, boundary_distance(outline, cuttable))
