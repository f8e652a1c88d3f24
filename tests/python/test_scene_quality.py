"""Geometry, labelling, quality and valence helpers of scene building (numpy only)."""

from __future__ import annotations

import numpy as np
import pytest
from hapticut.scenebuild.geometry import (
    TET_FACES,
    boundary_faces,
    enclosure_surface,
    face_pairs,
    interface_faces,
    kuhn_grid,
    signed_volume,
    tet_signed_volumes,
    winding_numbers,
)
from hapticut.scenebuild.labels import components, innermost
from hapticut.scenebuild.quality import dihedral_angles_deg, material_counts, tet_quality, valence

REGULAR_TET = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float)


def icosahedron_fan():
    """The icosahedron's centre (vertex 0) in 20 tets: the paper's VERTEX set-up."""
    t = (1 + 5**0.5) / 2
    outer = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float
    )  # fmt: skip
    faces = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    )  # fmt: skip
    vertices = np.vstack([[0, 0, 0], outer])
    return vertices, np.column_stack([np.zeros(20, int), faces + 1])


def test_a_regular_tet_has_every_dihedral_angle_arccos_one_third():
    angles = dihedral_angles_deg(REGULAR_TET, np.array([[0, 1, 2, 3]]))
    np.testing.assert_allclose(angles, np.degrees(np.arccos(1 / 3)), atol=1e-9)
    quality = tet_quality(REGULAR_TET, np.array([[0, 1, 2, 3]]))  # this order is negative
    assert quality["slivers"] == 0 and quality["inverted_or_flat"] == 1
    assert tet_quality(REGULAR_TET, np.array([[0, 1, 3, 2]]))["inverted_or_flat"] == 0


def test_a_flat_tet_is_counted_as_a_sliver():
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.3, 0.3, 0.01]])
    assert tet_quality(flat, np.array([[0, 1, 2, 3]]))["slivers"] == 1


def test_valence_of_the_icosahedron_fan_and_a_kuhn_cell():
    vertices, tets = icosahedron_fan()
    assert valence(tets) == {
        "edges": 42,
        "max_tets_per_edge": 5,
        "mean_tets_per_edge": pytest.approx((12 * 5 + 30 * 2) / 42, abs=1e-3),
        "max_tets_per_vertex": 20,
        "mean_tets_per_vertex": pytest.approx((20 + 12 * 5) / 13, abs=1e-3),
    }
    _, cell = kuhn_grid(np.zeros(3), np.ones(3), (1, 1, 1))
    assert valence(cell)["max_tets_per_edge"] == 6  # all six share the main diagonal


def test_kuhn_grid_fills_its_box_with_positive_tets():
    vertices, tets = kuhn_grid(np.zeros(3), np.array([2.0, 3.0, 4.0]), (2, 3, 2))
    volumes = tet_signed_volumes(vertices, tets)
    assert np.all(volumes > 0)
    assert volumes.sum() == pytest.approx(24.0)
    assert len(boundary_faces(tets)) == 2 * (2 * 3 + 3 * 2 + 2 * 2) * 2


@pytest.mark.parametrize("kind", ["box", "cube", "tetrahedron"])
def test_enclosures_are_closed_outward_and_hold_the_box(kind):
    low, high = np.array([0.0, 0, 0]), np.array([4.0, 2, 1])
    vertices, faces = enclosure_surface(kind, low, high, 0.5)
    assert signed_volume(vertices, faces) > 0
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, uses = np.unique(edges, axis=0, return_counts=True)
    assert np.all(uses == 2)
    corners = np.array([[x, y, z] for x in (-0.5, 4.5) for y in (-0.5, 2.5) for z in (-0.5, 1.5)])
    assert np.all(winding_numbers(corners * 0.999 + 0.001 * corners.mean(0), vertices, faces) > 0.5)
    assert len(faces) == (4 if kind == "tetrahedron" else 12)


def test_tet_faces_point_out_of_a_positive_tet():
    tet = np.array([[0, 1, 2, 3]])
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    assert tet_signed_volumes(vertices, tet)[0] > 0
    assert signed_volume(vertices, tet[0][TET_FACES]) > 0


def test_winding_numbers_inside_outside_and_off_the_box():
    vertices, tets = kuhn_grid(np.zeros(3), np.ones(3), (1, 1, 1))
    surface = boundary_faces(tets)
    points = np.array([[0.5, 0.5, 0.5], [0.1, 0.9, 0.2], [1.5, 0.5, 0.5], [-3, -3, -3]])
    np.testing.assert_allclose(winding_numbers(points, vertices, surface), [1, 1, 0, 0], atol=1e-9)


def test_interface_faces_bound_a_tet_set():
    vertices, tets = kuhn_grid(np.zeros(3), np.array([2.0, 1, 1]), (2, 1, 1))
    left = vertices[tets].mean(axis=1)[:, 0] < 1
    faces = interface_faces(tets, left)
    assert signed_volume(vertices, faces) == pytest.approx(1.0)
    pairs, _, boundary = face_pairs(tets)
    assert len(pairs) * 2 + len(boundary) == 4 * len(tets)


def test_components_and_innermost():
    pairs = np.array([[0, 1], [1, 2], [4, 5], [6, 5]])
    labels = components(7, pairs)
    assert labels[0] == labels[1] == labels[2] != labels[3]
    assert labels[4] == labels[5] == labels[6] != labels[0]
    inside = np.array([[1, 1, 0], [0, 1, 0]], dtype=bool)  # region 1 (smaller) inside region 0
    assert innermost(inside, np.array([10.0, 2.0])).tolist() == [0, 1, -1]
    assert material_counts(np.array([0, 2, 2]), ["air", "a", "b"]) == {"air": 1, "a": 0, "b": 2}
