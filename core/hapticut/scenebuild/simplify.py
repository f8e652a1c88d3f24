"""Simplifying a surface to the fewest faces within a tolerance (pymeshlab's quadric edge
collapse; the surface kept is measured against the whole input with its Hausdorff distance).

A try is a decimation and a measurement. Decimating the whole input and measuring a candidate
against all of it cost about the same, and both grow with the input, so on a scan the search
spends them once each:
- the first try decimates the input; a try below a try that fitted is decimated from that one
  (a few collapses more, not the whole input again), and a try just below a candidate that
  fitted from that candidate. On a scan that first decimation checks no face flip, unless
  it made a face cross another (then it is made again with the check);
- the tries steer the search with a screening measure (every input vertex, and as many face
  samples; the way back from the candidate only when the way from the input comes near the
  tolerance); the candidate the search ends on is then measured as every kept surface is
  (hausdorff's own sample count, both ways), and one that misses there is a miss like any
  other.
The face count to try is predicted from the tries so far (a decimated smooth surface's
deviation falls about as its face count grows), halving the bracket where the prediction does
not help.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .geometry import Surface, signed_volume
from .repair import _meshlab, crossing_faces, hausdorff

# The search stops when the fewest faces known to fit and the most known not to lie within
# this share of each other: a few faces more change little of what fTetWild makes of them.
FACE_COUNT_PRECISION = 0.1
# At most this many tries (decimations measured); the one known to fit best is kept.
MAX_ATTEMPTS = 8
# Tries a search usually makes (the progress expects them).
EXPECTED_ATTEMPTS = 4
# The first try keeps this share of the faces, or FIRST_FACES_PER_SIZE faces per tolerance
# in the surface's size (its bounding box's diagonal) when that is fewer. A surface kept at
# a tolerance needs about that ratio of faces times a factor of its shape: from under 1 (a
# finger's bones) to 13 (the bunny, a cow) at 0.2% to 0.4% of the size. The tries below it
# are decimated from it, and their deviation adds to its own (their quadrics know only it),
# so it stays well within the tolerance: at 60 the bunny's first try deviates a fifth of it
# (at 20 a half, and the search kept 40% more faces). On scans of over 60,000 faces the
# tries then start from thousands of faces rather than a quarter of the scan's.
FIRST_SHARE = 0.25
FIRST_FACES_PER_SIZE = 60.0
# A predicted face count is aimed this share above the prediction (the deviation falls in
# steps as faces are added, and a try that fits narrows the search more than one that
# misses); each try lies at least this share of the bracket (in log face count) above its
# lower end, the most faces known to miss.
AIM_ABOVE = 0.5 * FACE_COUNT_PRECISION
BRACKET_MARGIN = 0.1
# The margin counts at most this span of the bracket (a factor of 4 in face count): while
# nothing has missed, the bracket reaches down to min_faces, and a tenth of that would hold
# a prediction far from where it points.
MARGIN_SPAN = math.log(4.0)
# The screening measure samples at least this many points each way (and every vertex of the
# input): few enough to cost a small part of a full measure on a scan. From an input with as
# many vertices, it samples only them.
SCREEN_SAMPLES = 20_000
# The screen measures its way back (from the candidate to the input, 4 times the cost of the
# way from the input on a scan) only when the way from the input finds more than this share
# of the tolerance: below it, the way back found at most 1.3 times as much on the examples
# and pymeshlab's samples (mostly within 10%), so the try fits either way.
SCREEN_BACK_SHARE = 0.8
# A try at most this share below a candidate that fitted the screen is decimated from that
# candidate, not from the input's one decimation: a few collapses, where that candidate is
# flattest, so its largest deviation usually stays where it was. On the bunny, the cow and
# the finger's parts such a try fitted where one decimated from further up had missed, and
# the search kept up to 17% fewer faces (never more).
CHAIN_SHARE = 2 * FACE_COUNT_PRECISION


def simplify_surface(
    surface: Surface,
    tolerance_mm: float,
    min_faces: int = 20,
    on_attempt: Callable[[float], None] | None = None,
) -> tuple[Surface, int, float]:
    """The surface with as few faces as keep it within tolerance_mm of itself (Hausdorff).

    Quadric edge collapse (topology kept) to a face count searched for (module doc); the
    surface returned is measured both ways with pymeshlab's Hausdorff distance at its full
    sample count. Returns (surface, faces before, that deviation in mm). on_attempt(fraction
    of the work done) after each try and measure (a cancel raises from it).
    """
    pymeshlab = _meshlab()
    original = len(surface.faces)
    if tolerance_mm <= 0 or original <= min_faces:
        return surface, original, 0.0
    meshes = pymeshlab.MeshSet()
    meshes.add_mesh(pymeshlab.Mesh(vertex_matrix=surface.vertices, face_matrix=surface.faces))
    source = meshes.current_mesh_id()
    screen_samples = max(SCREEN_SAMPLES, len(surface.vertices))
    # An input of at least SCREEN_SAMPLES vertices is screened at its vertices alone (on the
    # bunny's tries its faces' samples found no more, and cost twice as much).
    fine_input = len(surface.vertices) >= SCREEN_SAMPLES
    size = float(np.linalg.norm(np.ptp(surface.vertices, axis=0)))
    first = min(FIRST_SHARE * original, FIRST_FACES_PER_SIZE * size / tolerance_mm)
    work = _Work(original, screen_samples, on_attempt)
    # Candidates decimated from the input that fitted, kept to decimate further from:
    # (face count, mesh id).
    bases: list[tuple[int, int]] = []

    def decimate(target: int) -> tuple[int, int]:
        """A candidate of about ``target`` faces: (its mesh id, the faces it started from)."""
        start, start_faces = source, original
        near = [(f, mesh_id) for f, mesh_id in screened if target * (1 + CHAIN_SHARE) >= f]
        for faces, mesh_id in bases + near:
            if target < faces < start_faces:
                start, start_faces = mesh_id, faces
        # A scan's first decimation, the search's dearest, skips the check that no face
        # flips (a quarter of its time) unless that made a face cross another.
        quick = fine_input and start == source and not bases
        for check_normals in (False, True) if quick else (True,):
            meshes.set_current_mesh(start)
            meshes.add_mesh(meshes.current_mesh(), "candidate")
            meshes.meshing_decimation_quadric_edge_collapse(
                targetfacenum=int(target),
                preservetopology=True,
                preservenormal=check_normals,
                optimalplacement=True,
                planarquadric=True,
                qualitythr=0.3,
            )
            if check_normals or not crossing_faces(meshes).any():
                break
            meshes.delete_current_mesh()
        return meshes.current_mesh_id(), start_faces

    def arrays(mesh_id: int) -> tuple[np.ndarray, np.ndarray]:
        mesh = meshes.mesh(mesh_id)
        return mesh.vertex_matrix().copy(), mesh.face_matrix().copy()

    best = (surface.vertices, surface.faces, 0.0)  # The fewest faces measured in full to fit.
    fits, misses = original, min_faces  # Face counts known to fit and (at most) not to.
    screened: list[tuple[int, int]] = []  # (faces, mesh id) that fit the screen, not measured.
    tries: list[tuple[int, float]] = []  # (faces, deviation) of each try.
    attempts = 0
    while True:
        if attempts < MAX_ATTEMPTS and fits - misses > max(4, FACE_COUNT_PRECISION * fits):
            attempts += 1
            target = next_face_count(misses, fits, tries, tolerance_mm, first)
            candidate, started_from = decimate(target)
            faces = meshes.mesh(candidate).face_number()
            deviation = hausdorff(
                meshes,
                source,
                candidate,
                screen_samples,
                first_vertices_only=fine_input,
                stop_above=tolerance_mm,
                back_from=math.inf,
            )
            if SCREEN_BACK_SHARE * tolerance_mm < deviation <= tolerance_mm:
                back = hausdorff(meshes, candidate, source, screen_samples, back_from=math.inf)
                deviation = max(deviation, back)
            tries.append((faces, deviation))
            work.decimated(started_from, faces)
            work.screened(attempts)
            if deviation <= tolerance_mm:
                fits = faces
                screened.append((faces, candidate))
                if started_from == original:
                    bases.append((faces, candidate))
                if faces > target:  # Decimation stopped early (topology): no gain below it.
                    misses = fits
            else:
                misses = max(misses, target)
                meshes.set_current_mesh(candidate)  # Nothing starts from a miss: free it.
                meshes.delete_current_mesh()
            continue
        if not screened:
            break
        # The search ends on the fewest faces that fit the screen: measure it in full.
        faces, candidate = min(screened)
        screened.remove((faces, candidate))
        deviation = hausdorff(
            meshes,
            source,
            candidate,
            between=lambda: work.measured(1 / 3),
            stop_above=tolerance_mm,
        )
        work.measured(2 / 3)
        if deviation <= tolerance_mm:
            best = (*arrays(candidate), deviation)
            break
        # A miss after all: search between it and the next that fitted the screen.
        tries.append((faces, deviation))
        misses = max(misses, faces)
        fits = min((f for f, _ in screened), default=original)
    vertices, faces, deviation = best
    faces = faces if signed_volume(vertices, faces) >= 0 else faces[:, ::-1]
    return (
        Surface(np.asarray(vertices, np.float64), np.asarray(faces, np.int32)),
        original,
        deviation,
    )


class _Work:
    """The search's progress as a share of its expected work, in decimations of the whole
    input: a decimation costs its share of the input's faces collapsed, a full measure about
    one decimation of the whole input and a screening measure its share of the full
    measure's samples (as they time on scans). Never goes back; below 1 until the caller's
    step ends."""

    # A try decimated from an earlier one collapses about this share of the input.
    CHAINED_TRY = 0.2

    def __init__(self, original: int, screen_samples: int, report) -> None:
        self.original = original
        self.full_measure = 1.0
        self.screen = min(screen_samples / (4 * original), 1.0)
        self.report = report
        self.done = 0.0
        self.attempts = 0  # Tries made.
        self.measuring = 0.0  # Full measures made (a fraction while one runs).
        self.reached = 0.0

    def decimated(self, start_faces: int, faces: int) -> None:
        self.done += max(start_faces - faces, 0) / self.original

    def screened(self, attempts: int) -> None:
        self.done += self.screen
        self.attempts = attempts
        self._tell()

    def measured(self, share: float) -> None:
        """``share`` of a full measure done (its first way, from the input's samples to the
        candidate's few faces, is the smaller share)."""
        self.measuring += share
        self.done += share * self.full_measure
        self._tell()

    def _tell(self) -> None:
        if self.report is None:
            return
        in_measure = self.measuring % 1.0
        if in_measure:
            left = (1.0 - in_measure) * self.full_measure
        elif self.measuring:  # A measure ended: the search ends unless it missed.
            left = self.CHAINED_TRY
        else:
            tries_left = max(EXPECTED_ATTEMPTS - self.attempts, 1)  # Past the usual: creep.
            left = tries_left * (self.CHAINED_TRY + self.screen) + self.full_measure
        self.reached = max(self.reached, self.done / (self.done + left))
        self.report(self.reached)


def next_face_count(
    misses: int,
    fits: int,
    tries: list[tuple[int, float]],
    tolerance_mm: float,
    first: float | None = None,
) -> int:
    """The next face count to try, strictly between ``misses`` (too few) and ``fits``.

    The first try keeps ``first`` faces (default FIRST_SHARE of them); later ones are
    predicted from the two tries nearest the tolerance (deviation ~ faces^-p, p from the two,
    or 1 from one) and aimed AIM_ABOVE above; the bracket's middle (in log face count) when
    the tries predict nothing (zero deviations, or no fall with more faces). Each try lies at
    least FACE_COUNT_PRECISION below the fewest faces that fit: a try there that misses, as
    a prediction just below them says it will, ends the search (a margin wider than the
    precision made it one try more). It lies at least FACE_COUNT_PRECISION and
    BRACKET_MARGIN of the bracket, up to MARGIN_SPAN, above the most that missed (so that a
    wrong prediction still narrows it: while nothing has missed, that end is min_faces).
    """
    low, high = math.log(max(misses, 1)), math.log(fits)
    step = max(BRACKET_MARGIN * min(high - low, MARGIN_SPAN), math.log1p(FACE_COUNT_PRECISION))
    lowest, highest = low + step, high - math.log1p(FACE_COUNT_PRECISION)
    if lowest > highest:  # A bracket narrower than its two margins: its middle ends the search.
        lowest = highest = (low + high) / 2
    measured = sorted(
        ((f, d) for f, d in tries if d > 0), key=lambda t: abs(math.log(t[1] / tolerance_mm))
    )
    if not tries:
        guess = math.log(first or FIRST_SHARE * fits)
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
