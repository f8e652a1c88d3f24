"""Which region holds each tet: winding numbers at the centroids, made robust near surfaces.

fTetWild's output surfaces follow the input within its envelope, not exactly, so a flat tet
against a surface may have its centroid on the wrong side of the *input* surface. Such
uncertain tets (centroid within the envelope of a surface) take the label of the region they
are connected to without crossing a surface: tets joined through faces that do not lie on
any input surface form components, and an uncertain tet takes its component's majority (by
volume) among the certain tets. A tet whose centroid is clear of every surface keeps its own
winding-number label, so a missed interface face can never flip a whole region.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .geometry import face_pairs, tet_signed_volumes, winding_numbers
from .repair import Surface, distance_to_surfaces

# Half a turn: the winding number of a closed outward surface is ~1 inside, ~0 outside.
INSIDE_WINDING = 0.5


def components(count: int, pairs: np.ndarray) -> np.ndarray:
    """(count,) component index per item, items joined by the (k, 2) index pairs."""
    parent = np.arange(count)
    if len(pairs) == 0:
        return parent
    a, b = pairs[:, 0], pairs[:, 1]
    while True:
        low = np.minimum(parent[a], parent[b])
        before = parent.copy()
        np.minimum.at(parent, a, low)
        np.minimum.at(parent, b, low)
        np.minimum.at(parent, before, parent)  # Hook old roots under the new minimum.
        while True:  # Pointer jumping: every item points at its root.
            jumped = parent[parent]
            if np.array_equal(jumped, parent):
                break
            parent = jumped
        if np.array_equal(parent, before):
            return np.unique(parent, return_inverse=True)[1]


def containment(
    vertices: np.ndarray,
    tets: np.ndarray,
    surfaces: list[Surface],
    envelope_mm: float,
    on_progress: Callable[[float], None] | None = None,
) -> tuple[np.ndarray, dict]:
    """(regions, m) bool: whether each tet lies inside each region's surface; and statistics.

    envelope_mm: how far fTetWild's surfaces may lie from the input (its epsilon).
    """
    centroids = vertices[tets].mean(axis=1)
    inside = np.zeros((len(surfaces), len(tets)), dtype=bool)
    total_faces = sum(len(s.faces) for s in surfaces) or 1
    done_faces = 0
    for r, surface in enumerate(surfaces):
        size = len(surface.faces)

        def chunk_done(fraction: float, done=done_faces, size=size) -> None:
            if on_progress is not None:
                on_progress(0.8 * (done + fraction * size) / total_faces)

        winding = winding_numbers(centroids, surface.vertices, surface.faces, chunk_done)
        inside[r] = winding > INSIDE_WINDING
        done_faces += len(surface.faces)

    # Near a surface: the centroid within the envelope (plus rounding) of some input surface.
    threshold = 1.5 * envelope_mm + 1e-9 * float(np.ptp(vertices, axis=0).max())
    centroid_distance = distance_to_surfaces(centroids, surfaces, 2 * threshold)
    uncertain = centroid_distance < threshold
    stats = {"uncertain_tets": int(uncertain.sum()), "relabelled_tets": 0}
    if not uncertain.any():
        return inside, stats
    vertex_distance = distance_to_surfaces(vertices, surfaces, 2 * threshold)
    pairs, shared, _ = face_pairs(tets)
    on_surface = np.all(vertex_distance[shared] < threshold, axis=1)
    component = components(len(tets), pairs[~on_surface])
    volume = np.abs(tet_signed_volumes(vertices, tets))
    certain = ~uncertain
    relabelled = np.zeros(len(tets), dtype=bool)
    for r in range(len(surfaces)):
        count = component.max() + 1
        votes_in = np.bincount(component[certain], volume[certain] * inside[r, certain], count)
        votes_all = np.bincount(component[certain], volume[certain], count)
        decided = votes_all[component] > 0
        majority = votes_in[component] > 0.5 * votes_all[component]
        change = uncertain & decided & (majority != inside[r])
        inside[r, change] = majority[change]
        relabelled |= change
    if on_progress is not None:
        on_progress(1.0)
    stats["relabelled_tets"] = int(relabelled.sum())
    return inside, stats


def innermost(inside: np.ndarray, volumes: np.ndarray) -> np.ndarray:
    """(m,) index of the smallest region holding each tet, or -1 where none does."""
    order = np.argsort(volumes)[::-1]  # Largest first; smaller (inner) ones overwrite.
    result = np.full(inside.shape[1], -1, dtype=np.int64)
    for r in order:
        result[inside[r]] = r
    return result
