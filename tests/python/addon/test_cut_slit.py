"""The cut's slit (addon/bake/cut_slit.py, numpy only): two sheets, each face offset along
its own normal, facing away from each other; a blade's half-thickness."""

import numpy as np
import pytest

from addon.bake import cut_slit

SQUARE = np.array([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.0)])
TRIANGLES = np.array([(0, 1, 2), (0, 2, 3)])


def test_the_sheets_lie_offset_each_side_and_face_away():
    vertices, faces, frames = cut_slit.slit(SQUARE, TRIANGLES, np.array([4, 7]), 0.25)
    assert vertices.shape == (12, 3) and faces.shape == (4, 3)
    assert list(frames) == [4, 7, 4, 7]
    assert np.allclose(vertices[:6, 2], 0.25) and np.allclose(vertices[6:, 2], -0.25)
    corners = np.vstack([SQUARE[TRIANGLES].reshape(-1, 3)] * 2)
    assert np.allclose(vertices[:, :2], corners[:, :2])
    assert np.allclose((vertices[:6] + vertices[6:]) / 2, corners[:6])  # Twins in order.
    assert normals(vertices, faces)[:2, 2].min() > 0 > normals(vertices, faces)[2:, 2].max()


def test_faces_wound_both_ways_stay_back_to_back():
    # The same square with its second triangle wound the other way (a sweep that turned):
    # averaged vertex normals would cancel on the shared edge; each face keeps its own.
    flipped = np.array([(0, 1, 2), (0, 3, 2)])
    vertices, faces, _ = cut_slit.slit(SQUARE, flipped, np.array([1, 1]), 0.5)
    facing = normals(vertices, faces)
    assert np.allclose(np.einsum("ij,ij->i", facing[:2], facing[2:]), -1.0)
    assert np.allclose(np.abs(vertices[:, 2]), 0.5)


def normals(vertices, faces):
    corners = vertices[faces]
    crossed = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    return crossed / np.linalg.norm(crossed, axis=1, keepdims=True)


def test_half_thickness():
    box = np.array([(x, y, z) for x in (0, 40) for y in (0, 8) for z in (0, 0.6)], float)
    assert cut_slit.half_thickness(box) == pytest.approx(0.3)
    assert cut_slit.half_thickness(SQUARE) == pytest.approx(0.0, abs=1e-12)
