"""The evaluation's valence sweep and surface truth: the reference fans have the
valence they claim, every timed case is the transition it names, and the
closest-point truth is exact. Pass or fail only; never time."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("hapticut._core")

from hapticut import _core  # noqa: E402
from hapticut_evaluation import meshes, surface, valence  # noqa: E402

FREE = [{"name": "air", "model": "free"}]


def centre_valence(mesh) -> int:
    v, t = mesh
    space = _core.Space(v, t, np.zeros(len(t), np.int32), FREE)
    assert space.stats["reoriented_tets"] == 0
    return int(np.count_nonzero(np.any(space.tets == 0, axis=1)))


@pytest.mark.parametrize("subdivisions", [0, 1, 2])
def test_geodesic_vertex_fan_has_20_x_4_to_the_k_tets(subdivisions):
    assert centre_valence(_core.vertex_fan_mesh(subdivisions)) == 20 * 4**subdivisions


@pytest.mark.parametrize("ring", [3, 7, 16])
def test_double_cone_centre_is_in_2n_tets(ring):
    assert centre_valence(_core.double_cone_mesh(ring)) == 2 * ring


def test_vertex_fan_rejects_bad_sizes():
    with pytest.raises(ValueError):
        _core.vertex_fan_mesh(-1)
    with pytest.raises(ValueError):
        _core.double_cone_mesh(2)


def test_each_timed_case_is_the_transition_it_names():
    rows = valence.edge_rows((4, 12), repeats=1, batches=1) + valence.vertex_rows(
        [valence.VERTEX_FANS[0], valence.VERTEX_FANS[-3]], repeats=1, batches=1
    )
    expected = {
        ("edge", "widen"): "EDGE->TET",
        ("edge", "scan"): "EDGE->EDGE",
        ("edge", "face"): "EDGE->FACE",
        ("vertex", "widen"): "VERTEX->TET",
        ("vertex", "stay"): "VERTEX->VERTEX",
        ("vertex", "face"): "VERTEX->FACE",
        ("vertex", "edge"): "VERTEX->EDGE",
    }
    assert len(rows) == 2 * 3 + 2 * 4
    for row in rows:
        assert row["transition"] == expected[(row["element"], row["case"])], row


def test_closest_points_on_a_sphere_are_exact_and_strokes_follow_it():
    vertices, triangles = meshes.icosphere(80)
    s = surface.SurfaceQueries(vertices, triangles)
    rng = np.random.default_rng(1)
    points = rng.normal(size=(200, 3)) * 40.0
    closest, tri, bary = s.closest(points)
    # Barycentric weights reproduce the point, and no sampled surface point is nearer.
    assert np.allclose(np.einsum("ij,ijk->ik", bary, vertices[triangles[tri]]), closest)
    u = np.linspace(0.0, 1.0, 25)
    uu, vv = (x[x + y <= 1] for x, y in [np.meshgrid(u, u), np.meshgrid(u, u)[::-1]])
    samples = (
        s.a[:, None]
        + (s.b - s.a)[:, None] * uu[None, :, None]
        + (s.c - s.a)[:, None] * vv[None, :, None]
    ).reshape(-1, 3)
    nearest_sample = np.array([np.linalg.norm(samples - p, axis=1).min() for p in points])
    assert np.all(nearest_sample >= np.linalg.norm(points - closest, axis=1) - 1e-9)
    path, slide = surface.strokes(s, 0.002, points=3, slide_s=0.2)
    # Pressed 2 mm along the smooth normal, which leans off the facet normal a little.
    below, _, _ = s.closest(path[slide].reshape(-1, 3))
    depth = np.linalg.norm(path[slide].reshape(-1, 3) - below, axis=1)
    assert np.all((depth > 1.8) & (depth <= 2.0 + 1e-9))
