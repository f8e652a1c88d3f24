"""Simplifying a surface to the fewest faces within a tolerance (pymeshlab's quadric edge
collapse, each candidate measured against the whole input with its Hausdorff distance).

Each try costs about the same (a decimation of the input and two Hausdorff distances over
it), so the search makes few: it predicts the face count from the tries so far (a
decimated smooth surface's deviation falls about as its face count grows) and falls back on
halving the bracket where the prediction does not help.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .geometry import Surface, signed_volume
from .repair import _meshlab, hausdorff

# The search stops when the fewest faces known to fit and the most known not to lie within
# this share of each other: a few faces more change little of what fTetWild makes of them.
FACE_COUNT_PRECISION = 0.1
# At most this many tries (decimations measured); the one known to fit best is kept.
MAX_ATTEMPTS = 8
# Tries a search usually makes: each is this share of the progress, until the last ones.
EXPECTED_ATTEMPTS = 4
# The first try keeps this share of the faces (scans in mm at the default accuracy keep
# from a twentieth to a half).
FIRST_SHARE = 0.25
# A predicted face count is aimed this share above the prediction (the deviation falls in
# steps as faces are added, and a try that fits narrows the search more than one that
# misses); each try lies at least this share of the bracket (in log face count) inside it.
AIM_ABOVE = 0.5 * FACE_COUNT_PRECISION
BRACKET_MARGIN = 0.1


def simplify_surface(
    surface: Surface,
    tolerance_mm: float,
    min_faces: int = 20,
    on_attempt: Callable[[float], None] | None = None,
) -> tuple[Surface, int, float]:
    """The surface with as few faces as keep it within tolerance_mm of itself (Hausdorff).

    Quadric edge collapse (topology kept) to a face count searched for (module doc), each
    candidate measured both ways with pymeshlab's Hausdorff distance. Returns (surface,
    faces before, the measured deviation in mm). on_attempt(fraction of the search done)
    after each try (a cancel raises from it).
    """
    pymeshlab = _meshlab()
    original = len(surface.faces)
    if tolerance_mm <= 0 or original <= min_faces:
        return surface, original, 0.0
    meshes = pymeshlab.MeshSet()
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=surface.vertices, face_matrix=surface.faces))
    source = meshes.current_mesh_id()

    def attempt(target: int):
        meshes.set_current_mesh(source)
        meshes.add_mesh(meshes.current_mesh(), "candidate")
        meshes.meshing_decimation_quadric_edge_collapse(
            targetfacenum=int(target),
            preservetopology=True,
            preservenormal=True,
            optimalplacement=True,
            planarquadric=True,
            qualitythr=0.3,
        )
        candidate = meshes.current_mesh_id()
        deviation = hausdorff(meshes, source, candidate)
        mesh = meshes.current_mesh()
        result = (mesh.vertex_matrix().copy(), mesh.face_matrix().copy(), deviation)
        meshes.delete_current_mesh()
        return result

    best = (surface.vertices, surface.faces, 0.0)  # The fewest faces known to fit.
    fits, misses = original, min_faces  # Face counts known to fit and (at most) not to.
    tries: list[tuple[int, float]] = []  # (faces, deviation) of each try.
    for number in range(1, MAX_ATTEMPTS + 1):
        if fits - misses <= max(4, FACE_COUNT_PRECISION * fits):
            break
        target = next_face_count(misses, fits, tries, tolerance_mm)
        vertices, faces, deviation = attempt(target)
        tries.append((len(faces), deviation))
        if on_attempt is not None:
            on_attempt(search_progress(number))
        if deviation <= tolerance_mm:
            fits, best = len(faces), (vertices, faces, deviation)
            if len(faces) > target:  # Decimation stopped early (topology): no gain below it.
                break
        else:
            misses = max(misses, target)
    vertices, faces, deviation = best
    faces = faces if signed_volume(vertices, faces) >= 0 else faces[:, ::-1]
    return (
        Surface(np.asarray(vertices, np.float64), np.asarray(faces, np.int32)),
        original,
        deviation,
    )


def next_face_count(
    misses: int, fits: int, tries: list[tuple[int, float]], tolerance_mm: float
) -> int:
    """The next face count to try, strictly between ``misses`` (too few) and ``fits``.

    The first try keeps FIRST_SHARE of the faces; later ones are predicted from the two
    tries nearest the tolerance (deviation ~ faces^-p, p from the two, or 1 from one) and
    aimed AIM_ABOVE above; the bracket's middle (in log face count) when the tries predict
    nothing (zero deviations, or no fall with more faces). Each try lies at least
    FACE_COUNT_PRECISION inside either end of the bracket (a try there that goes as predicted
    ends the search) and BRACKET_MARGIN of it (so that a wrong prediction still narrows it).
    """
    low, high = math.log(max(misses, 1)), math.log(fits)
    step = max(BRACKET_MARGIN * (high - low), math.log1p(FACE_COUNT_PRECISION))
    lowest, highest = low + step, high - step
    if lowest > highest:  # A bracket within twice the precision: its middle ends the search.
        lowest = highest = (low + high) / 2
    measured = sorted(
        ((f, d) for f, d in tries if d > 0), key=lambda t: abs(math.log(t[1] / tolerance_mm))
    )
    if not tries:
        guess = math.log(FIRST_SHARE * fits)
    elif not measured:
        guess = (low + high) / 2
    else:
        (faces_a, deviation_a), *rest = measured
        power = 1.0
        if rest and rest[0][0] != faces_a and rest[0][1] != deviation_a:
            faces_b, deviation_b = rest[0]
            power = math.log(deviation_b / deviation_a) / math.log(faces_a / faces_b)
        if 0.25 <= power <= 4.0:
            guess = math.log(faces_a) + math.log(deviation_a / tolerance_mm) / power
            guess += math.log1p(AIM_ABOVE)
        else:  # Noise, or a surface the model does not fit.
            guess = (low + high) / 2
    return _inside(math.exp(min(max(guess, lowest), highest)), misses, fits)


def _inside(target: float, misses: int, fits: int) -> int:
    return int(min(max(round(target), misses + 1), fits - 1))


def search_progress(tries_made: int) -> float:
    """The share of the search done after this many tries: even steps for the usual number
    of tries (each costs about the same), then creeping towards the end."""
    if tries_made <= EXPECTED_ATTEMPTS - 1:
        return tries_made / EXPECTED_ATTEMPTS
    beyond = tries_made - (EXPECTED_ATTEMPTS - 1)
    return 1 - (1 / EXPECTED_ATTEMPTS) / (1 + beyond)
