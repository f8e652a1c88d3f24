"""The simplification's search (scenebuild/simplify.py): few tries, each inside its bracket;
the surface kept measured in full; progress that never goes back."""

from __future__ import annotations

import math

import numpy as np
import pytest
from build_test_support import icosphere
from hapticut.scenebuild import simplify
from hapticut.scenebuild.geometry import Surface
from hapticut.scenebuild.simplify import next_face_count, simplify_surface


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


def test_a_prediction_just_below_the_fewest_that_fit_is_tried_where_a_miss_ends_the_search():
    """The bunny's tries (56k faces at 100 mm): the next predicted at about 2,320 faces, just
    below 2,294 that fit; tried at 2,294 / 1.1, so that a miss there ends the search."""
    tries = [(14_042, 0.127), (2_926, 0.498), (2_294, 0.622)]
    target = next_face_count(20, 2_294, tries, 0.641)
    assert target == round(2_294 / (1 + simplify.FACE_COUNT_PRECISION))
    assert 2_294 - target <= simplify.FACE_COUNT_PRECISION * 2_294


def test_the_first_try_on_a_large_surface_keeps_faces_per_tolerance_in_its_size(monkeypatch):
    vertices, faces = icosphere(30.0, 5)  # 20480 faces, 104 mm across its bounding box
    firsts = []
    real = simplify.next_face_count

    def recording(misses, fits, tries, tolerance, first=None):
        if not tries:
            firsts.append(first)
        return real(misses, fits, tries, tolerance, first)

    monkeypatch.setattr(simplify, "next_face_count", recording)
    simple, _, deviation = simplify_surface(Surface(vertices, faces), 3.0)
    size = math.dist(vertices.min(axis=0), vertices.max(axis=0))
    assert firsts == [pytest.approx(simplify.FIRST_FACES_PER_SIZE * size / 3.0)]
    assert firsts[0] < simplify.FIRST_SHARE * len(faces) and deviation <= 3.0


def test_a_flat_surface_keeps_its_few_faces_and_tells_its_progress():
    vertices, faces = icosphere(30.0, 3)  # 1280 faces
    seen = []
    simple, before, deviation = simplify_surface(
        Surface(vertices, faces), 0.3, on_attempt=seen.append
    )
    assert before == 1280 and len(simple.faces) < before and deviation <= 0.3
    assert seen == sorted(seen) and 0 < len(seen) <= simplify.MAX_ATTEMPTS


def concentric_spheres(*radii: float):
    """A MeshSet of icospheres about one centre: their Hausdorff distance is the radii's gap."""
    import pymeshlab

    meshes = pymeshlab.MeshSet()
    for radius in radii:
        vertices, faces = icosphere(radius, 2)
        meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=vertices, face_matrix=faces))
    return meshes


def test_a_way_that_finds_more_than_the_limit_ends_the_measure():
    """A screen or full measure whose first way misses does not measure the second."""
    meshes = concentric_spheres(30.0, 31.0)
    called = []
    stopped = simplify.hausdorff(meshes, 0, 1, between=lambda: called.append(1), stop_above=0.5)
    assert stopped == pytest.approx(1.0, abs=0.05) and not called
    both = simplify.hausdorff(meshes, 0, 1, between=lambda: called.append(1), stop_above=2.0)
    assert both == pytest.approx(1.0, abs=0.05) and called == [1]


def measures(monkeypatch, full_factor: float = 1.0):
    """Each Hausdorff measure the search makes as (faces measured, samples: None for the full
    count, deviation reported); full measures reported full_factor times what they found."""
    made = []
    real = simplify.hausdorff

    def recording(meshes, source, candidate, samples=None, between=None, **screen):
        deviation = real(meshes, source, candidate, samples, between, **screen)
        if samples is None:
            deviation *= full_factor
        made.append((meshes.mesh(candidate).face_number(), samples, deviation))
        return deviation

    monkeypatch.setattr(simplify, "hausdorff", recording)
    return made


def test_the_surface_kept_is_measured_in_full_and_the_tries_screened(monkeypatch):
    vertices, faces = icosphere(30.0, 4)  # 5120 faces
    made = measures(monkeypatch)
    simple, _, deviation = simplify_surface(Surface(vertices, faces), 0.5)
    full = [m for m in made if m[1] is None]
    assert full and full[-1][0] == len(simple.faces) and full[-1][2] == deviation <= 0.5
    assert len(full) < len(made)  # The tries were screened, not measured in full.


def test_a_candidate_that_misses_in_full_is_a_miss(monkeypatch):
    """The screen says it fits; the full measure says it does not: a surface with more faces,
    measured in full within the tolerance, is kept."""
    vertices, faces = icosphere(30.0, 4)
    made = measures(monkeypatch, full_factor=1.4)
    simple, _, deviation = simplify_surface(Surface(vertices, faces), 0.5)
    full = [m for m in made if m[1] is None]
    assert any(d > 0.5 for _, _, d in full)
    missed = min(f for f, _, d in full if d > 0.5)
    assert len(simple.faces) > missed
    assert 0 < deviation <= 0.5 and full[-1][:3:2] == (len(simple.faces), deviation)


def test_a_screen_below_its_share_of_the_tolerance_measures_one_way(monkeypatch):
    """The screen's way back (candidate to input) is measured only when the way from the
    input finds more than SCREEN_BACK_SHARE of the tolerance; the full measure always both."""
    meshes = concentric_spheres(30.0, 30.5)
    called = []
    one = simplify.hausdorff(meshes, 0, 1, between=lambda: called.append(1), back_from=1.0)
    assert one == pytest.approx(0.5, abs=0.05) and not called
    both = simplify.hausdorff(meshes, 0, 1, between=lambda: called.append(1), back_from=0.2)
    assert both == pytest.approx(0.5, abs=0.05) and called == [1]

    vertices, faces = icosphere(30.0, 4)
    made = []
    real = simplify.hausdorff

    def recording(meshes, first, second, samples=None, between=None, **screen):
        deviation = real(meshes, first, second, samples, between, **screen)
        made.append((first, samples, screen.get("back_from"), deviation))
        return deviation

    monkeypatch.setattr(simplify, "hausdorff", recording)
    simple, _, deviation = simplify_surface(Surface(vertices, faces), 0.5)
    screens = [m for m in made if m[1] is not None]
    from_input = [m for m in screens if m[0] == 0]
    back = [m for m in screens if m[0] != 0]
    assert from_input and all(m[2] is not None for m in screens)
    near = [m for m in from_input if simplify.SCREEN_BACK_SHARE * 0.5 < m[3] <= 0.5]
    assert len(back) == len(near)
    assert made[-1][1] is None and made[-1][3] == deviation <= 0.5


@pytest.mark.parametrize("crosses", [False, True])
def test_a_scans_first_decimation_skips_the_normal_check_unless_a_face_crosses(
    monkeypatch, crosses
):
    """On an input of SCREEN_SAMPLES vertices or more, the first decimation keeps no check
    that faces do not flip (the dearest step of the search); one that made a face cross
    another is decimated again with it. Either way the surface kept is measured in full
    within the tolerance, with about the faces of a search that checked every decimation."""
    vertices, faces = icosphere(30.0, 4)  # 2562 vertices
    surface = Surface(vertices, faces)
    careful, _, _ = simplify_surface(surface, 0.3)
    monkeypatch.setattr(simplify, "SCREEN_SAMPLES", 2_000)
    checks = []
    monkeypatch.setattr(
        simplify, "crossing_faces", lambda meshes: checks.append(1) or np.array([crosses])
    )
    decimations = []
    import pymeshlab

    original = pymeshlab.MeshSet.meshing_decimation_quadric_edge_collapse

    def recording(self, **options):
        decimations.append((options["preservenormal"], options["targetfacenum"]))
        return original(self, **options)

    monkeypatch.setattr(pymeshlab.MeshSet, "meshing_decimation_quadric_edge_collapse", recording)
    made = measures(monkeypatch)
    simple, _, deviation = simplify_surface(surface, 0.3)
    first = decimations[0][1]
    assert decimations[0] == (False, first) and checks == [1]
    assert all(check for check, _ in decimations[1:])
    assert (decimations[1][1] == first) == crosses
    assert made[-1][1] is None and made[-1][2] == deviation <= 0.3
    assert len(simple.faces) <= 1.25 * len(careful.faces)


def test_a_try_just_below_a_candidate_that_fitted_is_decimated_from_it(monkeypatch):
    """A try at most CHAIN_SHARE below a candidate that fitted the screen starts from that
    candidate (a few collapses); the surface kept is still measured in full against the
    input, within the tolerance."""
    import pymeshlab

    vertices, faces = icosphere(30.0, 5)  # 20480 faces
    decimations = []
    original = pymeshlab.MeshSet.meshing_decimation_quadric_edge_collapse

    def recording(self, **options):
        decimations.append((self.current_mesh().face_number(), options["targetfacenum"]))
        return original(self, **options)

    monkeypatch.setattr(pymeshlab.MeshSet, "meshing_decimation_quadric_edge_collapse", recording)
    made = measures(monkeypatch)
    simple, _, deviation = simplify_surface(Surface(vertices, faces), 0.2)
    first = made[0][0]  # The input's one decimation: the tries below start from it.
    chained = [(start, target) for start, target in decimations if start not in (20480, first)]
    assert chained and all(target * (1 + simplify.CHAIN_SHARE) >= s for s, target in chained)
    fitted = {f for f, samples, d in made if samples is not None and d <= 0.2}
    assert {start for start, _ in chained} <= fitted
    assert made[-1][1] is None and made[-1][0] == len(simple.faces)
    assert made[-1][2] == deviation <= 0.2
