"""hapticut.cut_clip (pure numpy): the edge's swept path cut back to the material, on
made-up sweeps where the material's outline is known exactly."""

import numpy as np
from hapticut import cut_clip, cut_surface

CENTRE, RADIUS = np.array([2.0, 2.0]), 1.7


def in_disc(points):
    """A disc of cuttable material in the plane z = 0 (its edge is the cut's outline)."""
    points = np.asarray(points).reshape(-1, 3)
    return np.linalg.norm(points[:, :2] - CENTRE, axis=1) < RADIUS


def out_of_rod(points):
    """Cuttable everywhere but a rod along x of radius 1 about y = 2, z = -0.5 (a bone)."""
    points = np.asarray(points).reshape(-1, 3)
    return np.hypot(points[:, 1] - 2.0, points[:, 2] + 0.5) > 1.0


def flat_sweep(rows=9, points=5):
    """An edge from x = 0 to 4 (points 1 apart) swept along y from 0 to 4, in z = 0."""
    q = np.zeros((rows, points, 3))
    q[:, :, 0] = np.linspace(0, 4, points)[None, :]
    q[:, :, 1] = np.linspace(0, 4, rows)[:, None]
    return q


def outline(vertices, faces):
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), 1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    return vertices[np.unique(unique[counts == 1])]


def clipped(q, cuttable):
    cutting = cuttable(q).reshape(q.shape[:2])
    allowed = np.ones((len(q) - 1, q.shape[1] - 1), bool)
    return cut_clip.clipped_sweep(q, cutting, allowed, np.arange(len(q)) + 1.0, cuttable)


def test_the_outline_is_the_materials_edge_not_the_quads():
    q = flat_sweep()
    vertices, faces, frames = clipped(q, in_disc)
    distance = np.linalg.norm(outline(vertices, faces)[:, :2] - CENTRE, axis=1)
    # Every outline vertex within the bisection's tolerance of the disc's edge.
    assert np.abs(distance - RADIUS).max() < 2 * cut_clip.CROSSING_TOLERANCE_MM
    # Whole quads whose four corners cut (the sweep the cut used to keep) step inside it.
    cutting = in_disc(q).reshape(q.shape[:2])
    whole = cut_surface.sweep(q, np.zeros(q.shape[:2]), np.arange(len(q)), frames, cutting)
    steps = RADIUS - np.linalg.norm(outline(whole.vertices, whole.faces)[:, :2] - CENTRE, axis=1)
    assert steps.max() > 0.5
    # The area is the disc's, to the outline's chords.
    corners = vertices[faces]
    area = (
        np.linalg.norm(
            np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
        ).sum()
        / 2
    )
    assert abs(area - np.pi * RADIUS**2) < 0.02 * np.pi * RADIUS**2
    # A face keeps the frame of the later row of its quad.
    assert frames.min() >= 2 and frames.max() <= len(q)


def test_where_the_sweep_ends_the_outline_is_the_edge():
    # Material everywhere: the outline is the sweep's own border (first and last rows, the
    # edge's ends), not a row or a column short of it.
    q = flat_sweep()
    vertices, faces, _ = clipped(q, lambda p: np.ones(len(np.asarray(p).reshape(-1, 3)), bool))
    border = outline(vertices, faces)
    on_border = np.isclose(border[:, 0], 0) | np.isclose(border[:, 0], 4)
    on_border |= np.isclose(border[:, 1], 0) | np.isclose(border[:, 1], 4)
    assert on_border.all()


def test_a_face_across_a_bone_is_split_and_cut_back_not_dropped_whole():
    # The edge slides over the rod at z = 0.45, under its top (z = 0.5 at y = 2): its rows at
    # y = 1.5 and 2.5 are out of the rod, but the faces between them cross it where
    # |y - 2| < 0.31. Those faces are split and cut back to the rod, not dropped whole.
    q = flat_sweep()[[0, 1, 2, 3, 5, 6, 7, 8]]
    q[:, :, 2] = 0.45
    vertices, faces, _ = clipped(q, out_of_rod)
    corners = vertices[faces]
    assert out_of_rod(corners.mean(axis=1)).all()
    assert out_of_rod(((corners + np.roll(corners, 1, axis=1)) / 2).reshape(-1, 3)).all()
    assert out_of_rod(vertices).all()
    band = 2 * np.sqrt(1 - 0.95**2)  # Where the plane is in the rod, across y.
    assert area(corners) > 4 * (4 - band) - 0.1  # Dropping the quads whole leaves 12.
    assert area(corners) < 4 * (4 - band) + 1e-6


def area(corners):
    crossed = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return np.linalg.norm(crossed, axis=1).sum() / 2


def test_rows_are_added_where_the_edge_jumped():
    q = flat_sweep(rows=41)  # 0.1 a tick along y.
    q[22:, :, 2] = 10.0  # A jump of 10 in one tick, between the rows 20 and 25.
    rows = cut_clip.rows_along_path(q, np.arange(0, 41, 5))
    assert set(rows) >= set(range(0, 41, 5))
    assert 22 in rows  # The tick after the jump: the sweep goes up with it, not through.
    steady = cut_clip.rows_along_path(flat_sweep(rows=41), np.arange(0, 41, 5))
    assert steady.tolist() == list(range(0, 41, 5))


def test_a_sliver_is_folded_into_its_neighbour_not_left_as_a_crack():
    # Two faces meet a cap sliver (0, 1, 2) along its short edges; the face (0, 3, 1) lies
    # across its long edge. Dropped alone, the sliver leaves an outline inside the surface
    # (0-1 on one side, 0-2 and 2-1 on the other); folded, the face across is split at 2.
    vertices = np.array(
        [[0.0, 0, 0], [1, 0, 0], [0.5, 1e-9, 0], [0.5, -1, 0], [0.25, 1, 0], [0.75, 1, 0]]
    )
    faces = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 4], [2, 1, 5], [2, 5, 4]])
    assert cut_clip.slivers(vertices, faces).tolist() == [True, False, False, False, False]
    kept, source = cut_clip.without_slivers(vertices, faces, np.arange(len(faces)))
    edges = np.sort(np.concatenate([kept[:, [0, 1]], kept[:, [1, 2]], kept[:, [2, 0]]]), 1)
    unique, counts = np.unique(edges, axis=0, return_counts=True)
    assert [0, 2] in unique[counts == 2].tolist() and [1, 2] in unique[counts == 2].tolist()
    assert [0, 1] not in unique.tolist()
    assert sorted(source.tolist()) == [1, 1, 2, 3, 4]
    assert abs(area(vertices[kept]) - area(vertices[faces])) < 1e-6
