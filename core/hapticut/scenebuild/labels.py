"""Which region holds each tet: winding numbers at the centroids, made robust near surfaces.

fTetWild's output surfaces follow the input within its envelope, not exactly, so a flat tet
against a surface may have its centroid on the wrong side of the *input* surface. Such
uncertain tets (centroid within the envelope of a surface) take the label of the region they
are connected to without crossing a surface: tets joined through faces that do not lie on
any input surface form components, and an uncertain tet takes its component's majority (by
volume) among the certain tets. Certain tets (centroid clear of every surface) are labelled
by winding numbers at a few samples per component; a component whose samples disagree (a
missed interface face) has every certain centroid evaluated, so such a face can never flip
a whole region.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .geometry import Surface, face_pairs, tet_signed_volumes, winding_numbers
from .repair import distance_to_surfaces

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

    Linear in the tets: tets joined through faces that lie on no input surface form
    components, and every certain tet (centroid clear of every surface) of a component lies
    on the same side of each surface. So the winding number is evaluated only at a few
    certain centroids spread over each component; when they agree, the component's certain
    tets take that label, and only a component whose samples disagree (a surface face that
    fTetWild missed) has every certain centroid evaluated, as a per-tet labelling would.
    """
    centroids = vertices[tets].mean(axis=1)
    # Near a surface: the centroid within the envelope (plus rounding) of some input surface.
    threshold = 1.5 * envelope_mm + 1e-9 * float(np.ptp(vertices, axis=0).max())
    centroid_distance = distance_to_surfaces(centroids, surfaces, 2 * threshold)
    uncertain = centroid_distance < threshold
    certain = ~uncertain
    vertex_distance = distance_to_surfaces(vertices, surfaces, 2 * threshold)
    pairs, shared, _ = face_pairs(tets)
    on_surface = np.all(vertex_distance[shared] < threshold, axis=1)
    component = components(len(tets), pairs[~on_surface])
    count = int(component.max()) + 1 if len(tets) else 0
    samples = _component_samples(component, certain, count)

    inside = np.zeros((len(surfaces), len(tets)), dtype=bool)
    stats = {"uncertain_tets": int(uncertain.sum()), "components": count}
    evaluated = 0
    for r, surface in enumerate(surfaces):
        winding = winding_numbers(centroids[samples], surface.vertices, surface.faces)
        sample_inside = winding > INSIDE_WINDING
        evaluated += len(samples)
        # Per component: how many samples are inside, and how many there are.
        inside_votes = np.bincount(component[samples], sample_inside, count)
        sample_count = np.bincount(component[samples], minlength=count)
        split = (inside_votes > 0) & (inside_votes < sample_count)
        inside[r] = (inside_votes[component] > 0) & certain
        recheck = np.flatnonzero(certain & split[component])
        if len(recheck):
            winding = winding_numbers(centroids[recheck], surface.vertices, surface.faces)
            inside[r, recheck] = winding > INSIDE_WINDING
            evaluated += len(recheck)
        if on_progress is not None:
            on_progress(0.8 * (r + 1) / len(surfaces))
    stats["winding_points"] = evaluated

    if uncertain.any():
        volume = np.abs(tet_signed_volumes(vertices, tets))
        for r in range(len(surfaces)):
            votes_in = np.bincount(component[certain], volume[certain] * inside[r, certain], count)
            votes_all = np.bincount(component[certain], volume[certain], count)
            decided = votes_all[component] > 0
            majority = votes_in[component] > 0.5 * votes_all[component]
            # An uncertain tet in a component without certain tets keeps its own winding number.
            lone = np.flatnonzero(uncertain & ~decided)
            if len(lone):
                surface = surfaces[r]
                winding = winding_numbers(centroids[lone], surface.vertices, surface.faces)
                inside[r, lone] = winding > INSIDE_WINDING
                evaluated += len(lone)
            voted = uncertain & decided
            inside[r, voted] = majority[voted]
        stats["voted_tets"] = int((uncertain & decided).sum())
        stats["winding_points"] = evaluated
    if on_progress is not None:
        on_progress(1.0)
    return inside, stats


# Certain centroids sampled per component: enough that a component crossing a surface is
# very unlikely to show one side only, few enough that labelling stays linear.
SAMPLES_PER_COMPONENT = 8


def _component_samples(component: np.ndarray, certain: np.ndarray, count: int) -> np.ndarray:
    """Indices of up to SAMPLES_PER_COMPONENT certain tets per component, evenly spread
    over the component's tets in index order (fTetWild numbers tets roughly in space)."""
    members = np.flatnonzero(certain)
    order = members[np.argsort(component[members], kind="stable")]
    sizes = np.bincount(component[order], minlength=count)
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    picks = []
    for k in range(SAMPLES_PER_COMPONENT):
        offset = (sizes * (2 * k + 1)) // (2 * SAMPLES_PER_COMPONENT)
        picks.append((starts + offset)[sizes > 0])
    return np.unique(order[np.concatenate(picks)]) if len(order) else order


def innermost(inside: np.ndarray, volumes: np.ndarray) -> np.ndarray:
    """(m,) index of the smallest region holding each tet, or -1 where none does."""
    order = np.argsort(volumes)[::-1]  # Largest first; smaller (inner) ones overwrite.
    result = np.full(inside.shape[1], -1, dtype=np.int64)
    for r in order:
        result[inside[r]] = r
    return result
