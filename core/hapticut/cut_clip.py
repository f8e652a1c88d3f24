"""The swept path of the edge, clipped to the cuttable material (pure numpy, with
hapticut.cut_surface).

The edge sweeps a ruled surface: the quads between its points at consecutive rows. Which
points cut is decided per point, by the tet it is in (``cut_surface.cuttable_points``); a
surface made of whole quads whose corners cut has an outline that steps by a quad or a tet.
Here the quads are split along the edge into finer columns, each triangle of them is kept
where its corners cut, and a triangle with corners on both sides is cut back to where the
edge leaves the material, found by bisection between a corner inside and one outside. So the
outline follows the material's surface where the edge leaves it, and the edge's own path
where the sweep ends (the back of the cut), to the bisection's tolerance, not to the tets.
A triangle whose corners are in but whose middle is not (a flat face beside a curved bone)
is split in four and cut back again, a few times, before the cut surface drops what is left.
"""

from __future__ import annotations

import numpy as np

# The most columns a gap between two points of the edge is split into: enough for an outline
# finer than the rows' spacing, without a long stroke's mesh growing past what Blender holds
# lightly.
MAX_COLUMNS_PER_GAP = 8
# A row where no point went this share of the rows' usual step from the row before is left
# out (the blade was held still): far above a sliver's width, far below what a render shows.
STILL_SHARE = 0.05
# A face narrower than this share of the largest coordinate is dropped: far above what
# float32 corners round by, so its normal in Blender holds.
SLIVER_SHARE = 1e-5
# Where the straight path between two rows leaves the material, ticks this share of the
# rows' usual step apart are added between them: the quads' dip into a bone shrinks with
# the square of their width.
FINE_SHARE = 0.125
# How many times a triangle that still crosses out of the material (a flat face beside a
# curved bone) is split in four and cut back again: each halves what the surface drops there.
SPLITS = 3
# Where the bisection stops: a crossing is placed within this of the material's boundary (mm).
CROSSING_TOLERANCE_MM = 1e-3
# How far a corner of the surface keeps inside the material along each axis (mm): a mesh's
# float32 corners are rounded, and a corner a hair inside would round out of it; this is
# well above that rounding on any scene Blender shows in millimetres.
FIRM_MM = 1e-4


def firmly_inside(points: np.ndarray, cuttable) -> np.ndarray:
    """(k,) bool: the point, and the six FIRM_MM from it along the axes, are in the material."""
    points = np.asarray(points, np.float64).reshape(-1, 3)
    offsets = np.concatenate([np.zeros((1, 3)), FIRM_MM * np.eye(3), -FIRM_MM * np.eye(3)])
    probes = (points[:, None, :] + offsets[None]).reshape(-1, 3)
    return cuttable(probes).reshape(-1, len(offsets)).all(axis=1)


def rows_along_path(q: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The rows (ticks into q (T, N, 3)), with ticks added between two of them where the edge
    went further than the rows' usual step, and rows where it stood still left out: a jump
    (the blade slipping off a bone within a few ticks) swept between two rows alone would be
    a flat quad through the bone, which the surface drops, while the ticks between follow the
    edge round it."""
    q = np.asarray(q, np.float64)
    rows = np.asarray(rows, np.int64)
    if len(rows) < 2:
        return rows
    steps = np.linalg.norm(np.diff(q[rows], axis=0), axis=-1).max(axis=1)
    moving = steps[steps > 0]
    if not len(moving):
        return rows
    usual = float(np.median(moving))
    chosen = [rows[:1]]
    for first, last in zip(rows[:-1], rows[1:], strict=True):
        between = q[first : last + 1]
        if np.linalg.norm(between - between[0], axis=-1).max() > 2 * usual:
            chosen.append(_ticks_a_step_apart(between, usual) + first)
        chosen.append(np.array([last]))
    still = max(CROSSING_TOLERANCE_MM, STILL_SHARE * usual)
    return _without_still_rows(q, np.unique(np.concatenate(chosen)), still)


def rows_over_material(q: np.ndarray, rows: np.ndarray, cutting: np.ndarray, firmly) -> np.ndarray:
    """The rows, with the ticks between two of them added (a FINE_SHARE of the rows' usual
    step apart) where both rows' points cut but the path straight between them leaves the
    material: a blade sliding over a bone rests on it, and a flat quad between two rows of
    the slide dips into the bone's curve, so the surface would lose a strip of it. Sampled
    at the columns the surface is split into, a quarter, half and three quarters across."""
    q = np.asarray(q, np.float64)
    rows = np.asarray(rows, np.int64)
    if len(rows) < 2 or q.shape[1] < 2:
        return rows
    parts = columns_per_gap(q[rows])
    share = (np.arange(parts) / parts)[None, None, :, None]
    fine = (1 - share) * q[rows][:, :-1, None] + share * q[rows][:, 1:, None]
    fine = fine.reshape(len(rows), -1, 3)  # (R, (N-1) parts, 3)
    cuts = np.repeat(cutting[:, :-1] & cutting[:, 1:], parts, axis=1)
    both = cuts[:-1] & cuts[1:]
    checked = np.flatnonzero(both.any(axis=1))
    leaving = np.zeros(len(rows) - 1, bool)
    for across in (0.25, 0.5, 0.75):
        if not len(checked):
            break
        middles = (1 - across) * fine[checked] + across * fine[checked + 1]
        inside = firmly(middles.reshape(-1, 3)).reshape(len(checked), -1)
        leaving[checked] |= (both[checked] & ~inside).any(axis=1)
    gaps = np.flatnonzero(leaving)
    if not len(gaps):
        return rows
    step = FINE_SHARE * _usual_step(q, rows)
    added = [_ticks_a_step_apart(q[rows[g] : rows[g + 1] + 1], step) + rows[g] for g in gaps]
    return np.unique(np.concatenate([rows, *added]))


def _usual_step(q: np.ndarray, rows: np.ndarray) -> float:
    """The median of the rows' steps where the edge moved (the most any point went)."""
    steps = np.linalg.norm(np.diff(q[rows], axis=0), axis=-1).max(axis=1)
    moving = steps[steps > 0]
    return float(np.median(moving)) if len(moving) else 0.0


def _without_still_rows(q: np.ndarray, rows: np.ndarray, still: float) -> np.ndarray:
    """The rows less those at which no point has gone ``still`` (mm) from the row kept before
    (the first and last kept): a blade held by a bone's friction creeps by microns, sweeping
    faces too thin to see, which the surface drops as slivers, and those would leave a crack
    along the edge where it rested."""
    kept = [rows[0]]
    for row in rows[1:-1]:
        if np.linalg.norm(q[row] - q[kept[-1]], axis=-1).max() >= still:
            kept.append(row)
    return np.array([*kept, rows[-1]], np.int64)


def _ticks_a_step_apart(path: np.ndarray, step: float) -> np.ndarray:
    """The ticks of path (K, N, 3), from its first, at which a point has gone further than
    step since the last tick taken."""
    taken, last = [], path[0]
    for k in range(1, len(path)):
        if np.linalg.norm(path[k] - last, axis=-1).max() > step:
            taken.append(k)
            last = path[k]
    return np.array(taken, np.int64)


def columns_per_gap(rows_q: np.ndarray) -> int:
    """How many columns each gap between two points is split into: about the rows' step
    along the path, so the triangles are about as long as they are wide."""
    if rows_q.shape[0] < 2 or rows_q.shape[1] < 2:
        return 1
    spacing = float(np.median(np.linalg.norm(np.diff(rows_q, axis=1), axis=-1)))
    steps = np.linalg.norm(np.diff(rows_q, axis=0), axis=-1)
    moving = steps[steps > 0]
    if not len(moving) or spacing <= 0:
        return 1
    return int(np.clip(np.ceil(spacing / float(np.median(moving))), 1, MAX_COLUMNS_PER_GAP))


def split_columns(
    rows_q: np.ndarray, cutting: np.ndarray, quad_ok: np.ndarray, parts: int, cuttable, firmly
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows with each gap split into ``parts`` columns: points (R, M, 3), which cut
    (R, M) (the points' own ``cutting``, the new ones by ``cuttable``, both firmly: settle),
    and the quads allowed (R-1, M-1). ``cuttable`` and ``firmly`` take (k, 3) points."""
    count, points = rows_q.shape[:2]
    share = np.arange(parts) / parts
    left, right = rows_q[:, :-1, None, :], rows_q[:, 1:, None, :]
    split = (1 - share)[None, None, :, None] * left + share[None, None, :, None] * right
    grid = np.concatenate([split.reshape(count, -1, 3), rows_q[:, -1:]], axis=1)
    inside = np.zeros(grid.shape[:2], bool)
    original = np.arange(points) * parts
    new = np.setdiff1d(np.arange(grid.shape[1]), original)
    # The points' own cut; a point a hair from leaving the material (FIRM_MM: a blade resting
    # on a bone) is moved off it by a hair, else taken as out.
    inside[:, original] = cutting
    if len(new):
        inside[:, new] = cuttable(grid[:, new].reshape(-1, 3)).reshape(count, -1)
    firm = firmly(grid[inside])
    loose = np.flatnonzero(inside.reshape(-1))[~firm]
    flat = grid.reshape(-1, 3)
    moved, settled = settle(flat[loose], cuttable, firmly)
    flat[loose] = moved
    inside.reshape(-1)[loose] = settled
    return flat.reshape(grid.shape), inside, np.repeat(quad_ok, parts, axis=1)


def settle(points: np.ndarray, cuttable, firmly) -> tuple[np.ndarray, np.ndarray]:
    """Points in the material but within FIRM_MM of leaving it, each moved twice FIRM_MM away
    from the axis steps that leave it: the points (moved where that made them firm) and which
    are firm. Moving keeps the point a corner of the faces either side of it (a row where the
    blade rested on a bone, swept into from above and out of sideways), where taking it as
    out would part them by a crack."""
    if not len(points):
        return points, np.zeros(0, bool)
    offsets = np.concatenate([FIRM_MM * np.eye(3), -FIRM_MM * np.eye(3)])
    probes = (points[:, None, :] + offsets[None]).reshape(-1, 3)
    leaving = ~cuttable(probes).reshape(len(points), -1)
    away = -(leaving[:, :, None] * offsets[None]).sum(axis=1)
    length = np.linalg.norm(away, axis=1, keepdims=True)
    away = np.divide(away, length, out=np.zeros_like(away), where=length > 0)
    moved = points + 2 * FIRM_MM * away
    firm = firmly(moved)
    return np.where(firm[:, None], moved, points), firm


def triangles(quad_ok: np.ndarray, columns: int) -> tuple[np.ndarray, np.ndarray]:
    """The two triangles of each allowed quad, as grid vertex ids (row * columns + column),
    and the row each quad starts at."""
    r, j = np.nonzero(quad_ok)
    a = r * columns + j
    b, c, d = a + 1, a + columns + 1, a + columns
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return faces, np.concatenate([r, r])


def crossings(
    starts: np.ndarray, ends: np.ndarray, cuttable, firmly
) -> tuple[np.ndarray, np.ndarray]:
    """Where each segment from a point in the material (starts) to one out of it (ends)
    leaves it: the last point found inside, by bisection."""
    inside, outside = starts.copy(), ends.copy()
    longest = float(np.max(np.linalg.norm(ends - starts, axis=1))) if len(starts) else 0.0
    rounds = int(np.ceil(np.log2(max(longest / CROSSING_TOLERANCE_MM, 1.0))))
    for _ in range(rounds):
        middle = (inside + outside) / 2
        found = cuttable(middle)
        inside[found] = middle[found]
        outside[~found] = middle[~found]
    # Back from the boundary by the tolerance (where still inside): the last point found in
    # may lie a hair from it, and a mesh's float32 corners would round it out.
    back = starts - inside
    length = np.linalg.norm(back, axis=1, keepdims=True)
    share = np.divide(CROSSING_TOLERANCE_MM, length, out=np.zeros_like(length), where=length > 0)
    within = inside + np.minimum(share, 1.0) * back
    safe = firmly(within) if len(within) else np.zeros(0, bool)
    inside[safe] = within[safe]
    settled, firm = settle(inside[~safe], cuttable, firmly)
    inside[~safe] = settled
    safe[~safe] = firm
    return inside, safe


def clip(
    points: np.ndarray, inside: np.ndarray, faces: np.ndarray, cuttable, firmly
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The triangles (faces into points, flagged by inside) cut back to the material: the
    vertices (the points, then the crossings), their flags (a crossing's: placed firmly in),
    the faces, and for each face its triangle."""
    flags = inside[faces]
    count = flags.sum(axis=1)
    whole = np.flatnonzero(count == 3)
    # Turn each mixed triangle (winding kept) so its lone corner, in or out, comes first.
    lone_in = count == 1
    mixed = np.flatnonzero((count == 1) | (count == 2))
    lone = np.where(lone_in[mixed, None], flags[mixed], ~flags[mixed]).argmax(axis=1)
    turned = faces[mixed][np.arange(len(mixed))[:, None], (lone[:, None] + np.arange(3)) % 3]
    # The crossings on the lone corner's two edges, each edge once.
    first, second = turned[:, [0, 1]], turned[:, [0, 2]]
    pairs = np.concatenate([first, second])
    inner_first = lone_in[mixed]
    inner_first = np.concatenate([inner_first, inner_first])
    oriented = np.where(inner_first[:, None], pairs, pairs[:, ::-1])  # (inside, outside)
    unique, which = np.unique(oriented, axis=0, return_inverse=True)
    which = which.reshape(-1)
    crossed, firm = crossings(points[unique[:, 0]], points[unique[:, 1]], cuttable, firmly)
    ids = len(points) + which
    x1, x2 = ids[: len(mixed)], ids[len(mixed) :]
    v0, v1, v2 = turned[:, 0], turned[:, 1], turned[:, 2]
    one = lone_in[mixed]
    # One corner in: the triangle at it. Two in (the lone one out): the quad beside them.
    tip = np.stack([v0, x1, x2], 1)[one]
    foot = np.concatenate([np.stack([x1, v1, v2], 1)[~one], np.stack([x1, v2, x2], 1)[~one]])
    faces_out = np.concatenate([faces[whole], tip, foot])
    source = np.concatenate([whole, mixed[one], mixed[~one], mixed[~one]])
    return np.concatenate([points, crossed]), np.concatenate([inside, firm]), faces_out, source


def faces_inside(vertices: np.ndarray, flags: np.ndarray, faces: np.ndarray, firmly) -> np.ndarray:
    """(f,) bool: the face's corners are flagged firmly in (a crossing that could not be
    placed firmly is not) and its samples are (samples_inside)."""
    return flags[faces].all(axis=1) & samples_inside(vertices, faces, firmly)


def samples_inside(vertices: np.ndarray, faces: np.ndarray, firmly) -> np.ndarray:
    """(f,) bool: the face's centre and its edges' midpoints are firmly in the material (a
    mesh's float32 corners move them too)."""
    corners = vertices[faces]
    samples = np.stack(
        [corners.mean(axis=1), *((corners + np.roll(corners, -1, axis=1)) / 2).transpose(1, 0, 2)],
        axis=1,
    )
    return firmly(samples.reshape(-1, 3)).reshape(-1, 4).all(axis=1)


def split_in_four(
    vertices: np.ndarray, inside: np.ndarray, faces: np.ndarray, firmly
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each face split at its edges' midpoints into four (winding kept, the four of a face in
    a row): the vertices with the midpoints added, their flags, the new faces, and each split
    edge as (its two ends, its midpoint)."""
    a, b, c = faces[:, 0], faces[:, 1], faces[:, 2]
    count = len(vertices)
    middles = np.concatenate(
        [(vertices[a] + vertices[b]) / 2, (vertices[b] + vertices[c]) / 2,
         (vertices[c] + vertices[a]) / 2]
    )  # fmt: skip
    ab = count + np.arange(len(faces))
    bc, ca = ab + len(faces), ab + 2 * len(faces)
    quarters = np.stack(
        [np.stack(corners, 1) for corners in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))],
        axis=1,
    ).reshape(-1, 3)
    points = np.concatenate([vertices, middles])
    halved = np.stack(
        [np.concatenate([a, b, c]), np.concatenate([b, c, a]), np.arange(count, len(points))], 1
    )
    return points, np.concatenate([inside, firmly(middles)]), quarters, halved


def conform(
    faces: np.ndarray, source: np.ndarray, halved: np.ndarray, count: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The faces with every face that has a split edge (a neighbour was split in four) split
    in two at its midpoint, until none has: no crack where a split face meets a whole one.
    ``halved`` (k, 3): an edge's two ends and its midpoint; ``count`` the vertices. Also
    which faces are new halves."""
    low, high = np.minimum(halved[:, 0], halved[:, 1]), np.maximum(halved[:, 0], halved[:, 1])
    keys = low * count + high
    order = np.argsort(keys)
    keys, middles = keys[order], halved[order, 2]
    new = np.zeros(len(faces), bool)
    for _ in range(4 * SPLITS):
        found = np.full(len(faces), -1, np.int64)
        which = np.zeros(len(faces), np.int64)
        for edge in range(3):
            a, b = faces[:, edge], faces[:, (edge + 1) % 3]
            key = np.minimum(a, b) * count + np.maximum(a, b)
            at = np.clip(np.searchsorted(keys, key), 0, len(keys) - 1)
            hit = (keys[at] == key) & (found < 0)
            found[hit], which[hit] = middles[at[hit]], edge
        split = np.flatnonzero(found >= 0)
        if not len(split):
            break
        turned = faces[split][
            np.arange(len(split))[:, None], (which[split, None] + np.arange(3)) % 3
        ]
        a, b, c, m = turned[:, 0], turned[:, 1], turned[:, 2], found[split]
        halves = np.concatenate([np.stack([a, m, c], 1), np.stack([m, b, c], 1)])
        keep = found < 0
        faces = np.concatenate([faces[keep], halves])
        source = np.concatenate([source[keep], source[split], source[split]])
        new = np.concatenate([new[keep], np.ones(len(halves), bool)])
    return faces, source, new


def slivers(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(f,) bool: the face is narrower than SLIVER_SHARE of the largest coordinate (a crossing
    a hair from a corner makes one). Nothing to see, and in a mesh's float32 corners its
    normal is noise, so the slit's two sheets of it would not face apart."""
    if not len(faces):
        return np.zeros(0, bool)
    corners = vertices[faces]
    doubled = np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    longest = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max(axis=1)
    return doubled < SLIVER_SHARE * float(np.abs(vertices).max()) * longest


def without_slivers(
    vertices: np.ndarray, faces: np.ndarray, source: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The faces without their slivers, and each one's source. A sliver's corner opposite its
    longest edge lies on that edge (within the sliver's width): the face across the edge is
    split at that corner (conform) so the faces either side of the sliver still meet along
    its two short edges, where dropping it alone would leave an outline inside the surface.
    Pieces that are slivers in turn are dropped."""
    thin = slivers(vertices, faces)
    if not thin.any():
        return faces, source
    corners = vertices[faces[thin]]
    lengths = np.linalg.norm(np.roll(corners, -1, axis=1) - corners, axis=2)  # edge k: k, k+1
    longest = lengths.argmax(axis=1)
    turned = faces[thin][np.arange(len(longest))[:, None], (longest[:, None] + np.arange(3)) % 3]
    faces, source, _ = conform(faces[~thin], source[~thin], turned, len(vertices))
    solid = ~slivers(vertices, faces)
    return faces[solid], source[solid]


def clipped_sweep(
    rows_q: np.ndarray,
    cutting: np.ndarray,
    quad_ok: np.ndarray,
    row_frames: np.ndarray,
    cuttable,
    firmly=None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The swept path clipped to the material (module doc): vertices, faces and each face's
    frame (the frame the edge reached the quad's later row at). ``cuttable(points)`` says
    which (k, 3) points are in the material, ``firmly(points)`` which are FIRM_MM inside it
    (firmly_inside by default)."""
    if firmly is None:

        def firmly(points):
            return firmly_inside(points, cuttable)

    rows_q = np.asarray(rows_q, np.float64)
    parts = columns_per_gap(rows_q)
    grid, inside, allowed = split_columns(rows_q, cutting, quad_ok, parts, cuttable, firmly)
    columns = grid.shape[1]
    faces, face_rows = triangles(allowed, columns)
    vertices, inside, faces, source = clip(
        grid.reshape(-1, 3), inside.reshape(-1), faces, cuttable, firmly
    )
    # Which faces have their samples in the material: checked once each, as faces come.
    passed = faces_inside(vertices, inside, faces, firmly)
    halved = []  # (edge's two ends, its midpoint) of every edge split.
    for _ in range(SPLITS):
        if passed.all():
            break
        leaving = ~passed
        points, flags, quarters, middles = split_in_four(vertices, inside, faces[leaving], firmly)
        halved.append(middles)
        vertices, inside, pieces, piece_source = clip(points, flags, quarters, cuttable, firmly)
        faces = np.concatenate([faces[passed], pieces])
        source = np.concatenate([source[passed], np.repeat(source[leaving], 4)[piece_source]])
        passed = np.concatenate([passed[passed], faces_inside(vertices, inside, pieces, firmly)])
    # What still leaves the material after the splits is dropped (a sliver at the boundary).
    faces, source = faces[passed], source[passed]
    if halved:
        faces, source, new = conform(faces, source, np.concatenate(halved), len(vertices))
        # A half whose corner is a midpoint out of the material is cut back like any face.
        vertices, inside, pieces, piece_source = clip(
            vertices, inside, faces[new], cuttable, firmly
        )
        pieces_source = source[new][piece_source]
        whole = faces_inside(vertices, inside, pieces, firmly)
        faces = np.concatenate([faces[~new], pieces[whole]])
        source = np.concatenate([source[~new], pieces_source[whole]])
    faces, source = without_slivers(vertices, faces, source)
    frames = np.ceil(np.asarray(row_frames)[face_rows[source] + 1] - 1e-9).astype(np.int32)
    used, compact = np.unique(faces, return_inverse=True)
    return vertices[used], compact.reshape(-1, 3).astype(np.int32), frames
