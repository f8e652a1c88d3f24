"""The simplification's search (scenebuild/simplify.py): few tries, each inside its bracket,
and progress in even steps."""

from __future__ import annotations

import math

import pytest
from build_test_support import icosphere
from hapticut.scenebuild import simplify
from hapticut.scenebuild.geometry import Surface
from hapticut.scenebuild.simplify import next_face_count, search_progress, simplify_surface


def search(deviation_at, original: int, tolerance: float) -> tuple[int, list[int]]:
    """The search's face count and its tries on a made-up deviation curve."""
    tries, fits, misses, tried = [], original, 20, []
    for _ in range(simplify.MAX_ATTEMPTS):
        if fits - misses <= max(4, simplify.FACE_COUNT_PRECISION * fits):
            break
        target = next_face_count(misses, fits, tries, tolerance)
        assert misses < target < fits
        tried.append(target)
        deviation = deviation_at(target)
        tries.append((target, deviation))
        if deviation <= tolerance:
            fits = target
        else:
            misses = target
    return fits, tried


@pytest.mark.parametrize("power", [0.5, 1.0, 2.0])
@pytest.mark.parametrize("answer", [300, 2_500, 30_000])
def test_the_search_finds_a_smooth_curves_face_count_in_few_tries(power, answer):
    """Deviation falling as faces^-power reaches the tolerance at ``answer`` faces."""
    tolerance = 1.0
    found, tried = search(lambda f: (answer / f) ** power, 60_000, tolerance)
    assert answer <= found <= answer * (1 + 2 * simplify.FACE_COUNT_PRECISION)
    assert len(tried) <= simplify.EXPECTED_ATTEMPTS + 1


def test_the_search_ends_within_its_precision_on_a_stepped_curve():
    """A deviation that falls in steps (one feature decides it) still brackets the answer."""

    def stepped(faces: int) -> float:
        return 2.0 if faces < 1_000 else 1.2 if faces < 3_100 else 0.4

    found, tried = search(stepped, 6_000, 0.5)
    assert 3_100 <= found <= 3_100 * (1 + simplify.FACE_COUNT_PRECISION) + 4
    assert len(tried) <= simplify.MAX_ATTEMPTS


def test_zero_deviations_halve_the_bracket_in_log_face_count():
    target = next_face_count(100, 10_000, [(10_000 // 4, 0.0)], 1.0)
    assert target == pytest.approx(math.sqrt(100 * 10_000), rel=0.01)


def test_progress_moves_in_even_steps_then_creeps_below_the_end():
    steps = [search_progress(n) for n in range(1, simplify.MAX_ATTEMPTS + 1)]
    assert steps == sorted(steps) and steps[-1] < 1.0
    usual = steps[: simplify.EXPECTED_ATTEMPTS - 1]
    assert usual == pytest.approx(
        [n / simplify.EXPECTED_ATTEMPTS for n in range(1, len(usual) + 1)]
    )


def test_a_flat_surface_keeps_its_few_faces_and_tells_its_progress():
    vertices, faces = icosphere(30.0, 3)  # 1280 faces
    seen = []
    simple, before, deviation = simplify_surface(
        Surface(vertices, faces), 0.3, on_attempt=seen.append
    )
    assert before == 1280 and len(simple.faces) < before and deviation <= 0.3
    assert seen == sorted(seen) and 0 < len(seen) <= simplify.MAX_ATTEMPTS
