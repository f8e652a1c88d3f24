"""Holding the accuracy: where a build cannot, it says what was lost (the strict
mode's error: test_scene_build.py); inputs whose size suggests other units than mm are
warned about."""

from __future__ import annotations

import numpy as np
import pytest
from build_test_support import icosphere
from hapticut.scenebuild import BuildSettings, Region, build, builder, units_warning
from hapticut.scenebuild.geometry import (
    Surface,
    buried_faces,
    enclosure_surface,
    ray_hit_distances,
)
from hapticut.scenebuild.report import accuracy_lines, figures_apart
from hapticut.scenefile import Material

BONE = Material("bone", "rigid")


def test_rays_from_inside_a_ball_hit_it_at_its_radius():
    vertices, faces = icosphere(10.0, 3)
    directions = np.array([[1.0, 0, 0], [0, -1.0, 0], [0, 0.6, 0.8]])
    hits = ray_hit_distances(np.zeros((3, 3)), directions, vertices, faces)
    assert np.all((hits > 9.5) & (hits <= 10.0 + 1e-9))
    # From a point on the surface, inwards: the ball's thickness there (its diameter).
    start = vertices[:1]
    inward = -start / np.linalg.norm(start)
    assert ray_hit_distances(start, inward, vertices, faces)[0] == pytest.approx(20.0, abs=0.1)
    # Outwards from outside: nothing.
    assert ray_hit_distances(start * 2, -inward, vertices, faces)[0] == np.inf


def test_faces_of_a_surface_crossing_itself_inside_its_own_volume_are_buried():
    left = icosphere(10.0, 2, centre=(-5.0, 0.0, 0.0))
    right = icosphere(10.0, 2, centre=(5.0, 0.0, 0.0))
    vertices = np.vstack([left[0], right[0]])
    faces = np.vstack([left[1], right[1] + len(left[0])])
    buried = buried_faces(vertices, faces, 0.01)
    centres = vertices[faces].mean(axis=1)
    # Faces of the left ball inside the right one (and the converse) are buried, the rest not.
    inside_other = np.where(
        np.arange(len(faces)) < len(left[1]),
        np.linalg.norm(centres - [5.0, 0, 0], axis=1) < 9.5,
        np.linalg.norm(centres - [-5.0, 0, 0], axis=1) < 9.5,
    )
    clear = np.abs(np.where(np.arange(len(faces)) < len(left[1]),
                            np.linalg.norm(centres - [5.0, 0, 0], axis=1),
                            np.linalg.norm(centres - [-5.0, 0, 0], axis=1)) - 10) > 0.5  # fmt: skip
    assert np.array_equal(buried[clear], inside_other[clear])
    assert buried.sum() > 50
    # A ball alone buries nothing.
    assert not buried_faces(*icosphere(10.0, 2), 0.01).any()


def test_lost_features_are_found_with_their_thickness():
    """The input: a ball with a thin fin (2 mm by 1 mm by 8 mm) sticking out of it; the
    'meshed' surface: the ball alone. The fin is the one lost feature, about 1 mm thick."""
    ball = icosphere(10.0, 3)
    fin_v = np.array([[x, y, z] for x in (8.0, 16.0) for y in (-1.0, 1.0) for z in (-0.5, 0.5)])
    fin_f = np.array(
        [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
         [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
    )  # fmt: skip
    whole = Surface(np.vstack([ball[0], fin_v]), np.vstack([ball[1], fin_f + len(ball[0])]))
    meshed = Surface(*ball)
    features, points = builder._lost_features(whole, whole, meshed, accuracy_mm=2.0)
    assert len(features) == 1
    (fin,) = features
    assert fin["thickness_mm"] == pytest.approx(1.0, abs=0.05)
    assert fin["deviation_mm"] == pytest.approx(6.0, abs=0.1)
    assert 12.0 < fin["centre_mm"][0] < 16.0
    assert np.all(points[0][:, 0] > 10.0)


def _stray(monkeypatch, attempts):
    # An envelope three times the accuracy lets fTetWild's surface stray beyond it.
    monkeypatch.setattr(builder, "ENVELOPE_SHARE", 3.0)
    monkeypatch.setattr(builder, "MESHING_ATTEMPTS", attempts)


def test_a_build_beyond_the_accuracy_keeps_the_best_mesh_and_says_so(monkeypatch):
    _stray(monkeypatch, 1)
    scene = build(
        [Region("ball", *icosphere(10.0, 2), BONE)], settings=BuildSettings(accuracy_mm=0.3)
    )
    report = scene.metadata["build_report"]
    (miss,) = report["accuracy_not_held"]
    assert miss["region"] == "ball" and miss["accuracy_mm"] == 0.3
    assert miss["deviation_mm"] == report["deviation_mm"]["ball"] > 0.3
    lines = accuracy_lines(report)
    assert lines[0].startswith("accuracy not held: region 'ball' lies up to")
    assert len(scene.tets) == report["tets"] > 0


def test_a_build_within_the_accuracy_reports_nothing_lost():
    scene = build(
        [Region("ball", *icosphere(10.0, 2), BONE)], settings=BuildSettings(accuracy_mm=0.3)
    )
    report = scene.metadata["build_report"]
    assert report["accuracy_not_held"] == [] and accuracy_lines(report) == []
    assert report["deviation_mm"]["ball"] <= 0.3
    assert "warnings" not in report
    air = report["tets_per_material"]["air"]
    assert report["air_share"] == pytest.approx(air / report["tets"], abs=1e-4)


@pytest.mark.parametrize(
    ("across", "warned"),
    [(2.0, True), (4.9, True), (5.0, False), (120.0, False), (5000.0, False), (6000.0, True)],
)
def test_units_are_questioned_under_5_mm_and_over_5_m(across, warned):
    warning = units_warning("cow", np.array([[0.0, 0.0, 0.0], [across, across / 2, 0.0]]))
    assert (warning is not None) == warned
    if warned:
        assert "region 'cow'" in warning and "--scale" in warning and "mm across" in warning


def test_a_2_mm_input_is_warned_about_in_the_report():
    cube = enclosure_surface("box", np.zeros(3), np.full(3, 2.0), 0.0)
    scene = build([Region("cow", *cube, BONE)])
    (warning,) = scene.metadata["build_report"]["warnings"]
    assert "is 2 mm across" in warning and "--scale 50 makes it 100 mm" in warning


def test_a_deviation_and_the_accuracy_it_is_beyond_are_worded_apart():
    assert figures_apart(1.2143, 1.2101) == ("1.214", "1.21")
    assert figures_apart(1.43, 1.21) == ("1.43", "1.21")
    report = {"accuracy_not_held": [{"region": "Cow", "deviation_mm": 1.2143, "accuracy_mm": 1.21,
              "lost_mm": 0.0, "strayed_mm": 1.2143, "lost_features": []}]}  # fmt: skip
    assert (
        "up to 1.214 mm from its input, beyond accuracy_mm (1.21 mm)" in accuracy_lines(report)[0]
    )
