"""Labelling by component votes gives the labels of a winding number at every centroid.

Each example is built for real (pymeshlab, pytetwild); the builder's labelling call is
observed, and its result compared with the per-tet definition computed here by brute force:
every certain centroid (clear of every surface) takes its own winding number, every uncertain
one its component's volume majority among the certain tets, or its own winding number when
its component has no certain tet.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
from build_test_support import EXAMPLES
from hapticut.scenebuild import builder, labels
from hapticut.scenebuild.geometry import face_pairs, tet_signed_volumes, winding_numbers
from hapticut.scenebuild.repair import distance_to_surfaces

sys.path.insert(0, str(EXAMPLES))
import build_examples  # noqa: E402


def per_tet_labels(vertices, tets, surfaces, envelope_mm) -> np.ndarray:
    centroids = vertices[tets].mean(axis=1)
    threshold = 1.5 * envelope_mm + 1e-9 * float(np.ptp(vertices, axis=0).max())
    uncertain = distance_to_surfaces(centroids, surfaces, 2 * threshold) < threshold
    vertex_distance = distance_to_surfaces(vertices, surfaces, 2 * threshold)
    pairs, shared, _ = face_pairs(tets)
    on_surface = np.all(vertex_distance[shared] < threshold, axis=1)
    component = labels.components(len(tets), pairs[~on_surface])
    count = component.max() + 1
    volume = np.abs(tet_signed_volumes(vertices, tets))
    certain = ~uncertain
    inside = np.zeros((len(surfaces), len(tets)), dtype=bool)
    for r, surface in enumerate(surfaces):
        own = winding_numbers(centroids, surface.vertices, surface.faces) > labels.INSIDE_WINDING
        votes_in = np.bincount(component[certain], volume[certain] * own[certain], count)
        votes_all = np.bincount(component[certain], volume[certain], count)
        decided = votes_all[component] > 0
        majority = votes_in[component] > 0.5 * votes_all[component]
        inside[r] = np.where(uncertain & decided, majority, own)
    return inside


@pytest.mark.parametrize("name", ["sphere320", "finger", "mouse"])
def test_component_votes_match_per_tet_winding_numbers(name, monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)  # fTetWild writes __tracked_surface.stl into the cwd.
    calls = []

    def observed(vertices, tets, surfaces, envelope_mm, on_progress=None):
        result = labels.containment(vertices, tets, surfaces, envelope_mm, on_progress)
        calls.append((vertices, tets, surfaces, envelope_mm, result))
        return result

    monkeypatch.setattr(builder, "containment", observed)
    scene, _ = build_examples.build_example(name)
    (vertices, tets, surfaces, envelope_mm, (inside, stats)) = calls[0]
    expected = per_tet_labels(vertices, tets, surfaces, envelope_mm)
    differing = np.flatnonzero(np.any(inside != expected, axis=0))
    assert len(differing) == 0, f"{name}: {len(differing)} tets labelled differently"
    assert stats["winding_points"] < len(tets) * len(surfaces)
    timings = scene.metadata["build_report"]["timings_s"]
    share = timings["label"] / timings["total"]
    print(
        f"\n{name}: {len(tets)} tets, {stats['components']} components, "
        f"{stats['winding_points']} winding points; labelling {timings['label']:.2f} s "
        f"of {timings['total']:.2f} s ({100 * share:.1f} %)"
    )
