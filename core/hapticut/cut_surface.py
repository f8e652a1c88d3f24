"""The cut surface of a stroke: where the blade's ideal points went through cuttable material.

Pure numpy (the Blender add-on loads this file from the toolkit, like ``servo_client``).
From a servo recording's proxies ``q`` (ticks, N, 3) and states, and the scene's tets:

- a point *cuts* at a tick when its proxy is inside a tet (state TET, not held on a face,
  edge or vertex) whose material is cuttable (drag, viscous, or a membrane it pierced) and,
  for a servo recording, that the engine cut (its cut order, which the recording carries:
  ``Recording.cut_order``); the cut tets (``CutSurface.cut_tets``) are then the engine's,
  so the surface a bake renders and the cut the hand felt are the same tets. Without the
  engine's set (proxies alone), they are the tets the cutting points were in at the rows;
- the surface is the edge's swept path (hapticut.cut_clip): rows of points are ticks picked
  at the scene's frames (``substeps`` per frame), and between them where the edge jumped
  further than the rows' usual step (``rows_along_path``); the quads between points i, i+1
  of rows r, r+1 whose points stayed inside tets at every tick between the rows are split into finer
  columns along the edge, and their triangles are kept where their corners cut, cut back to
  where the edge leaves the material (bisection) where only some do; a face carries the
  frame of row r+1 (when the blade got there). So the outline follows the edge's path and
  the material's surface, not the tets' steps.

Then every face whose centre or edge midpoint lies outside cuttable material is dropped (a
flat triangle between two points beside a curved bone would clip the bone's surface). So no
face lies in rigid material (its proxies stop on its surface) or in air, at those samples.

A bake computes them in a child process (``hapticut cut-surface``, ``recording_cut_surfaces``)
and reads its file back (``read_cut_surfaces``): on a large scene the computation takes
longer than Blender's UI may wait.
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass, field, replace

import numpy as np

from hapticut import cut_clip
from hapticut.atomic_file import write_atomically

CUTTABLE_MODELS = ("drag", "viscous", "membrane")
STATE_TET = 0  # ProxyState::Tet (core/include/hapticut/proxy.h)
# Barycentric tolerance of the point-in-tet test (a point on a shared face is in either tet).
INSIDE_TOLERANCE = 1e-9


def _inverses(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The inverses of (m, 3, 3) matrices given by their rows, and which are invertible (zero
    where not). Written out with cross products: LAPACK's batched 3x3 inverse goes through
    the BLAS threads, which spin for seconds on a machine whose cores are all busy."""
    r0, r1, r2 = rows[:, 0], rows[:, 1], rows[:, 2]
    columns = np.stack([np.cross(r1, r2), np.cross(r2, r0), np.cross(r0, r1)], axis=-1)
    determinants = np.einsum("ki,ki->k", r0, columns[:, :, 0])
    usable = determinants != 0
    inverse = np.zeros_like(rows)
    inverse[usable] = columns[usable] / determinants[usable, None, None]
    return inverse, usable


class TetLocator:
    """The tet holding each point, through a uniform grid of the tets' bounding boxes."""

    def __init__(self, vertices: np.ndarray, tets: np.ndarray, max_pairs: int = 4_000_000):
        self.vertices = np.asarray(vertices, np.float64)
        self.tets = np.asarray(tets, np.int64)
        corners = self.vertices[self.tets]  # (m, 4, 3)
        self.origin = corners[:, 0]
        edges = corners[:, 1:] - corners[:, :1]  # (m, 3, 3): rows b-a, c-a, d-a
        # lambda (b, c, d weights) = (x - a) @ inv(edges)
        self.inverse, self.usable = _inverses(edges)
        # Each tet's least height (three volumes over its largest face): a point whose
        # barycentric weights are all above d / height lies d or more inside it.
        faces = corners[:, [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]]  # (m, 4, 3, 3)
        areas = np.linalg.norm(
            np.cross(faces[:, :, 1] - faces[:, :, 0], faces[:, :, 2] - faces[:, :, 0]), axis=-1
        ).max(axis=1)
        volumes = np.abs(np.einsum("ki,ki->k", edges[:, 0], np.cross(edges[:, 1], edges[:, 2])))
        self.least_height = np.divide(volumes, areas, out=np.zeros(len(areas)), where=areas > 0)
        lo, hi = corners.min(axis=1), corners.max(axis=1)
        self.lo = lo.min(axis=0) if len(lo) else np.zeros(3)
        span = (hi.max(axis=0) - self.lo) if len(hi) else np.ones(3)
        cell = float(np.median(np.max(hi - lo, axis=1))) if len(lo) else 1.0
        while True:
            self.cell = max(cell, 1e-9)
            self.shape = np.maximum(1, np.ceil(span / self.cell).astype(np.int64) + 1)
            first = np.floor((lo - self.lo) / self.cell).astype(np.int64)
            last = np.floor((hi - self.lo) / self.cell).astype(np.int64)
            counts = np.prod(last - first + 1, axis=1)
            if counts.sum() <= max_pairs or cell > span.max():
                break
            cell *= 1.5
        self._build(first, last, counts)

    def _build(self, first: np.ndarray, last: np.ndarray, counts: np.ndarray) -> None:
        m = len(counts)
        tet_of_pair = np.repeat(np.arange(m), counts)
        offset = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        size = last - first + 1
        nx, ny = size[tet_of_pair, 0], size[tet_of_pair, 1]
        ix = first[tet_of_pair, 0] + offset % nx
        iy = first[tet_of_pair, 1] + (offset // nx) % ny
        iz = first[tet_of_pair, 2] + offset // (nx * ny)
        cells = (iz * self.shape[1] + iy) * self.shape[0] + ix
        order = np.argsort(cells, kind="stable")
        self.pair_tets = tet_of_pair[order]
        total = int(np.prod(self.shape))
        self.cell_start = np.searchsorted(cells[order], np.arange(total + 1))

    def locate(self, points: np.ndarray, chunk: int = 200_000) -> np.ndarray:
        """The index of a tet holding each point ((k, 3) -> (k,) int64), -1 outside them all."""
        return self.locate_with_depth(points, chunk)[0]

    def locate_with_depth(
        self, points: np.ndarray, chunk: int = 200_000
    ) -> tuple[np.ndarray, np.ndarray]:
        """locate, and for each point found a lower bound of its distance to its tet's faces
        (0 where not found)."""
        points = np.asarray(points, np.float64).reshape(-1, 3)
        out = np.full(len(points), -1, np.int64)
        depth = np.zeros(len(points))
        index = np.floor((points - self.lo) / self.cell).astype(np.int64)
        inside_grid = np.all((index >= 0) & (index < self.shape), axis=1) & np.all(
            np.isfinite(points), axis=1
        )
        which = np.flatnonzero(inside_grid)
        if not len(which):
            return out, depth
        i = index[which]
        cells = (i[:, 2] * self.shape[1] + i[:, 1]) * self.shape[0] + i[:, 0]
        start, stop = self.cell_start[cells], self.cell_start[cells + 1]
        counts = stop - start
        # Candidates in chunks of pairs (point, tet) so memory stays bounded.
        ends = np.cumsum(counts)
        begin = 0
        while begin < len(which):
            limit = (ends[begin - 1] if begin else 0) + chunk
            end = max(begin + 1, int(np.searchsorted(ends, limit, side="right")))
            some = (which[begin:end], start[begin:end], counts[begin:end])
            self._locate_some(points, *some, out, depth)
            begin = end
        return out, depth

    def _locate_some(self, points, which, start, counts, out, depth) -> None:
        total = int(counts.sum())
        if not total:
            return
        point_of_pair = np.repeat(np.arange(len(which)), counts)
        offset = np.arange(total) - np.repeat(np.cumsum(counts) - counts, counts)
        tets = self.pair_tets[np.repeat(start, counts) + offset]
        x = points[which[point_of_pair]] - self.origin[tets]
        weights = np.einsum("ki,kij->kj", x, self.inverse[tets])
        inside = (
            self.usable[tets]
            & np.all(weights >= -INSIDE_TOLERANCE, axis=1)
            & (weights.sum(axis=1) <= 1 + INSIDE_TOLERANCE)
        )
        hits = np.flatnonzero(inside)
        # The first hit per point (pairs are grouped by point, in order).
        points_hit, first = np.unique(point_of_pair[hits], return_index=True)
        out[which[points_hit]] = tets[hits[first]]
        chosen = hits[first]
        least = np.minimum(weights[chosen].min(axis=1), 1 - weights[chosen].sum(axis=1))
        depth[which[points_hit]] = np.maximum(least, 0) * self.least_height[tets[chosen]]


@dataclass
class CutSurface:
    vertices: np.ndarray  # (v, 3) mm
    faces: np.ndarray  # (f, 3) int32
    face_frames: np.ndarray  # (f,) int32: the scene frame each face was cut at
    cutting: np.ndarray  # (rows, N) bool: which point cut at each row
    row_ticks: np.ndarray  # (rows,) the recording index of each row
    # The tets the cutting points were in at the rows (sorted): the per-tet cut, which the
    # smooth surface above renders and does not change.
    cut_tets: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))


def cuttable_points(
    q: np.ndarray,
    states: np.ndarray,
    locator: TetLocator,
    tet_materials: np.ndarray,
    material_models,
) -> np.ndarray:
    """(…, N) bool: the proxy is in a tet (state TET) of a cuttable material."""
    return cutting_tets(q, states, locator, tet_materials, material_models) >= 0


def cutting_tets(
    q: np.ndarray,
    states: np.ndarray,
    locator: TetLocator,
    tet_materials: np.ndarray,
    material_models,
) -> np.ndarray:
    """(…, N) int64: the cuttable tet each proxy cuts in (state TET), -1 where it does not
    cut: the one decision of which points, and so which tets, a stroke cuts."""
    q = np.asarray(q, np.float64)
    shape = q.shape[:-1]
    cuttable_material = np.array([m in CUTTABLE_MODELS for m in material_models], bool)
    in_tet = np.asarray(states).reshape(-1) == STATE_TET
    found = np.full(in_tet.shape, -1, np.int64)
    found[in_tet] = locator.locate(q.reshape(-1, 3)[in_tet])
    material = np.where(found >= 0, np.asarray(tet_materials)[np.maximum(found, 0)], -1)
    ok = (found >= 0) & cuttable_material[np.maximum(material, 0)]
    return np.where(ok, found, -1).reshape(shape)


def nearest_ticks(times_s: np.ndarray, step_s: float, count: int) -> np.ndarray:
    """The index of the record nearest each of the times k * step_s, k < count (``times_s``
    increasing, from the stroke's start)."""
    times_s = np.asarray(times_s, np.float64)
    wanted = np.arange(count) * step_s
    index = np.clip(np.searchsorted(times_s, wanted), 0, max(len(times_s) - 1, 0))
    before = np.clip(index - 1, 0, None)
    nearer = np.abs(times_s[before] - wanted) < np.abs(times_s[index] - wanted)
    return np.where(nearer, before, index)


def covered_steps(times_s: np.ndarray, step_s: float) -> int:
    """How many of the times k * step_s the records cover (the first at 0)."""
    return int(np.floor(times_s[-1] / step_s + 1e-9)) + 1 if len(times_s) else 0


def frame_ticks(
    times_s: np.ndarray, fps: float, frame_start: int, frame_end: int | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """(the scene frames the recording covers, up to frame_end when given; the record nearest
    each): what a bake keys."""
    count = covered_steps(np.asarray(times_s, np.float64), 1.0 / fps)
    if frame_end is not None:
        count = min(count, max(frame_end - frame_start + 1, 0))
    return frame_start + np.arange(count), nearest_ticks(times_s, 1.0 / fps, count)


def row_ticks_at_frames(
    times_s: np.ndarray, fps: float, frame_start: int, substeps: int = 1
) -> tuple[np.ndarray, np.ndarray]:
    """(recording indices, their frames): the tick nearest each (sub)frame of the stroke.

    ``times_s`` are the records' times from the stroke's start (0 at frame_start)."""
    times_s = np.asarray(times_s, np.float64)
    if not len(times_s):
        return np.zeros(0, np.int64), np.zeros(0, np.float64)
    step = 1.0 / (fps * max(1, substeps))
    index = np.unique(nearest_ticks(times_s, step, covered_steps(times_s, step)))
    return index, frame_start + times_s[index] * fps


def stayed_in_tets(states: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """(rows-1, N) bool: the point stayed inside a tet at every tick between two consecutive
    rows (both rows included)."""
    rows = np.asarray(rows, np.int64)
    left_tet = (np.asarray(states) != STATE_TET).astype(np.int64)
    zeros = np.zeros((1, left_tet.shape[1]), np.int64)
    cumulative = np.concatenate([zeros, np.cumsum(left_tet, axis=0)])
    return (cumulative[rows[1:] + 1] - cumulative[rows[:-1]]) == 0


def allowed_quads(states: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """(rows-1, N-1) bool: the quads between points i, i+1 of consecutive rows whose two
    points stayed inside tets between the rows (a point held on a face, or out of the mesh,
    went round the material rather than through it)."""
    stayed = stayed_in_tets(states, rows)
    return stayed[:, :-1] & stayed[:, 1:]


def sweep(
    q: np.ndarray,
    states: np.ndarray,
    rows: np.ndarray,
    row_frames: np.ndarray,
    cutting_rows: np.ndarray,
) -> CutSurface:
    """The quads between consecutive rows whose four corners cut (module doc)."""
    q = np.asarray(q, np.float64)
    rows = np.asarray(rows, np.int64)
    count, points = len(rows), q.shape[1]
    if count < 2 or points < 2:
        return CutSurface(
            np.zeros((0, 3)),
            np.zeros((0, 3), np.int32),
            np.zeros(0, np.int32),
            cutting_rows,
            rows,
        )
    stayed = stayed_in_tets(states, rows)
    corner = cutting_rows[:-1] & cutting_rows[1:] & stayed  # point i cuts from row r to r+1
    keep = corner[:, :-1] & corner[:, 1:]  # (rows-1, N-1): the quad of points i, i+1
    r, i = np.nonzero(keep)
    a = r * points + i
    b = a + 1
    c = a + points + 1
    d = a + points
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    frames = np.ceil(np.asarray(row_frames)[r + 1] - 1e-9).astype(np.int32)
    face_frames = np.concatenate([frames, frames])
    used, compact = np.unique(faces, return_inverse=True)
    vertices = q[rows].reshape(-1, 3)[used]
    return CutSurface(
        vertices, compact.reshape(-1, 3).astype(np.int32), face_frames, cutting_rows, rows
    )


def keep_inside_cuttable(
    surface: CutSurface, locator: TetLocator, tet_materials: np.ndarray, material_models
) -> CutSurface:
    """The surface without the faces whose centre or an edge midpoint is not in a tet of
    cuttable material."""
    if not len(surface.faces):
        return surface
    corners = surface.vertices[surface.faces]  # (f, 3, 3)
    samples = np.stack(
        [
            corners.mean(axis=1),
            (corners[:, 0] + corners[:, 1]) / 2,
            (corners[:, 1] + corners[:, 2]) / 2,
            (corners[:, 2] + corners[:, 0]) / 2,
        ],
        axis=1,
    )  # (f, 4, 3)
    inside = cuttable_points(
        samples, np.full(samples.shape[:2], STATE_TET), locator, tet_materials, material_models
    ).all(axis=1)
    faces = surface.faces[inside]
    used, compact = np.unique(faces, return_inverse=True)
    return CutSurface(
        surface.vertices[used],
        compact.reshape(-1, 3).astype(np.int32),
        surface.face_frames[inside],
        surface.cutting,
        surface.row_ticks,
        surface.cut_tets,
    )


def cut_surface(
    q: np.ndarray,
    states: np.ndarray,
    times_s: np.ndarray,
    fps: float,
    frame_start: int,
    tet_vertices: np.ndarray,
    tets: np.ndarray,
    tet_materials: np.ndarray,
    material_models,
    substeps: int = 2,
    locator: TetLocator | None = None,
    engine_cut: np.ndarray | None = None,
) -> CutSurface:
    """The whole computation (module doc) for one blade of a recording; ``engine_cut``, the
    tets the engine cut (the recording's cut order), decides which tets cut."""
    locator = locator or TetLocator(tet_vertices, tets)
    rows, _ = row_ticks_at_frames(times_s, fps, frame_start, substeps)
    q = np.asarray(q, np.float64)
    rows = cut_clip.rows_along_path(q, rows)
    cuttable_material = np.array([m in CUTTABLE_MODELS for m in material_models], bool)
    materials = np.asarray(tet_materials)

    def located(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        tets, depth = locator.locate_with_depth(points)
        return (tets >= 0) & cuttable_material[materials[np.maximum(tets, 0)]], depth

    def cuttable(points: np.ndarray) -> np.ndarray:
        return located(points)[0]

    def firmly(points: np.ndarray) -> np.ndarray:
        # Only a point near its tet's faces may have a neighbour tet of another material
        # within FIRM_MM: those alone are probed along the axes.
        points = np.asarray(points, np.float64).reshape(-1, 3)
        inside, depth = located(points)
        near = inside & (depth <= cut_clip.FIRM_MM)
        inside[near] = cut_clip.firmly_inside(points[near], cuttable)
        return inside

    def cut_at(rows: np.ndarray) -> np.ndarray:
        found = cutting_tets(
            q[rows], np.asarray(states)[rows], locator, tet_materials, material_models
        )
        if engine_cut is None:
            return found
        return np.where(np.isin(found, engine_cut), found, -1)

    cut_in = cut_at(rows)
    finer = cut_clip.rows_over_material(q, rows, cut_in >= 0, firmly)
    if len(finer) > len(rows):
        rows, cut_in = finer, cut_at(finer)
    row_frames = frame_start + np.asarray(times_s, np.float64)[rows] * fps
    cutting = cut_in >= 0
    cut_tets = np.unique(cut_in[cutting] if engine_cut is None else engine_cut).astype(np.int64)
    if len(rows) < 2 or q.shape[1] < 2:
        return replace(sweep(q, states, rows, row_frames, cutting), cut_tets=cut_tets)
    vertices, faces, face_frames = cut_clip.clipped_sweep(
        q[rows], cutting, allowed_quads(states, rows), row_frames, cuttable, firmly
    )
    # Its faces' centres and edge midpoints are in the material already (cut_clip drops the
    # rest, the test keep_inside_cuttable makes of whole quads).
    return CutSurface(vertices, faces, face_frames, cutting, rows, cut_tets)


def preview_tets(path: str | os.PathLike) -> dict:
    """The tets a preview file holds (hapticut.preview): vertices, tets, materials, models."""
    with np.load(path) as data:
        return {
            "vertices": data["tet_vertices"],
            "tets": data["tets"],
            "materials": data["tet_materials"],
            "models": [str(m) for m in data["material_models"]],
        }


def recording_cut_surfaces(
    recording, tets: dict, fps: float, frame_start: int, substeps: int, ticks: int
) -> dict[str, CutSurface]:
    """Each blade's cut surface over the recording's first ``ticks`` records (a
    hapticut.recording.Recording; ``tets`` as preview_tets gives them), cut where the engine
    cut by the last of them (``Recording.cut_order``; the scene has one cut set, so every
    blade's ``cut_tets`` is the same). A recording whose records were dropped leaves a hole
    in that order: then the proxies decide alone (module doc)."""
    times = recording.elapsed_s()[:ticks]
    locator = TetLocator(tets["vertices"], tets["tets"])
    try:
        engine_cut = recording.cut_order(min(ticks, len(recording)) - 1) if ticks else None
    except ValueError:
        engine_cut = None
    surfaces = {}
    for name in recording.blade_names:
        blade = recording.blade(name)
        surfaces[name] = cut_surface(
            blade["q"][:ticks],
            blade["state"][:ticks],
            times,
            fps,
            frame_start,
            tets["vertices"],
            tets["tets"],
            tets["materials"],
            tets["models"],
            substeps=substeps,
            locator=locator,
            engine_cut=engine_cut,
        )
    return surfaces


def write_cut_surfaces(path: str | os.PathLike, surfaces: dict[str, CutSurface]) -> None:
    """The surfaces as .npz: ``names``, then ``vertices_i``, ``faces_i``, ``face_frames_i``,
    ``cutting_i``, ``row_ticks_i`` and ``cut_tets_i`` for the i-th name."""
    arrays: dict[str, np.ndarray] = {"names": np.array(list(surfaces), dtype=str)}
    for i, surface in enumerate(surfaces.values()):
        arrays[f"vertices_{i}"] = surface.vertices
        arrays[f"faces_{i}"] = surface.faces
        arrays[f"face_frames_{i}"] = surface.face_frames
        arrays[f"cutting_{i}"] = surface.cutting
        arrays[f"row_ticks_{i}"] = surface.row_ticks
        arrays[f"cut_tets_{i}"] = surface.cut_tets
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    write_atomically(path, buffer.getvalue())


def read_cut_surfaces(path: str | os.PathLike) -> dict[str, CutSurface]:
    """What write_cut_surfaces wrote."""
    with np.load(path) as data:
        return {
            str(name): CutSurface(
                data[f"vertices_{i}"],
                data[f"faces_{i}"],
                data[f"face_frames_{i}"],
                data[f"cutting_{i}"],
                data[f"row_ticks_{i}"],
                data[f"cut_tets_{i}"],
            )
            for i, name in enumerate(data["names"])
        }
