"""Surface meshes to a labelled tetrahedral scene: ``build(regions, blades, settings)``.

    from hapticut.scenefile import Material
    from hapticut.scenebuild import BuildSettings, Region, build
    bone = Region.from_file("bone.obj", Material("bone", "rigid"))
    flesh = Region.from_file("flesh.obj", Material("flesh", "drag", drag_distance_mm=1.0))
    scene = build([flesh, bone], settings=BuildSettings(enclosure="cube"))

Steps (docs/scene-building.md): check and repair each region (pymeshlab); simplify it to the
accuracy; check that regions do not cross; put an enclosure around them (the air's outer
boundary); a sizing field, fine near the region surfaces and coarser with distance; one
conforming tet mesh of the enclosure and every region (fTetWild); label each tet with the
material of the innermost region holding it (air outside every region); measure quality,
valence and the surfaces' deviation from the input. The report goes into
``scene.metadata["build_report"]``.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from ..scenefile.model import BladeSpec, Material, Scene
from . import tetwild
from .errors import BuildCancelled, BuildError
from .geometry import (
    Surface,
    boundary_faces,
    enclosure_planes,
    enclosure_surface,
    interface_faces,
    kuhn_grid,
    orient_tets,
    point_segment_distance,
    signed_volume,
    triangle_areas,
    winding_numbers,
)
from .labels import INSIDE_WINDING, containment, innermost
from .locality import in_locality_order
from .quality import mesh_report
from .repair import (
    distance_to_surfaces,
    read_surface,
    repair_surface,
    self_intersecting_faces,
    simplify_surface,
    surface_deviation,
)
from .report import BuildReport, SurfaceReport

__all__ = [
    "BuildCancelled",
    "BuildError",
    "BuildReport",
    "BuildSettings",
    "ProgressCallback",
    "RefineZone",
    "Region",
    "build",
]

ENCLOSURES = ("box", "cube", "tetrahedron")
# progress(fraction 0..1, message) -> False to cancel (None or True: go on).
ProgressCallback = Callable[[float, str], "bool | None"]
# Defaults relative to the regions' size (their bounding box): see BuildSettings.
DEFAULT_MARGIN_RATIO = 0.25
DEFAULT_ACCURACY_RATIO = 0.005
DEFAULT_FAR_RATIO = 4.0
# The background grid of the sizing field: at most this many cells along the longest side.
SIZING_GRID_CELLS = 32
# Shares of accuracy_mm: simplifying the input, and fTetWild's envelope. fTetWild keeps its
# output within the envelope of its input but not the converse, so a fifth is held back.
SIMPLIFY_SHARE = 0.4
ENVELOPE_SHARE = 0.4
# How often the tet mesh is made, halving the envelope each time, until every region's meshed
# surface lies within accuracy_mm of its input (when measure_deviation is on).
MESHING_ATTEMPTS = 3


@dataclass(frozen=True, eq=False)
class Region:
    """A closed surface mesh filled with one material (vertices (n, 3) mm, faces (f, 3))."""

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    material: Material

    @classmethod
    def from_file(
        cls,
        path: str | os.PathLike,
        material: Material,
        name: str | None = None,
        scale: float = 1.0,
    ) -> Region:
        """A region read from a mesh file (OBJ, PLY, STL, OFF...), named after the file."""
        if name is None:
            name = os.path.basename(os.fspath(path)).split(".")[0]
        try:
            vertices, faces = read_surface(path)
        except BuildError as error:
            raise BuildError(name, error.problem) from None
        return cls(name, np.asarray(vertices, np.float64) * scale, np.asarray(faces), material)


@dataclass(frozen=True)
class RefineZone:
    """A capsule (segment start-end, radius) meshed with edges of at most edge_mm: a blade's
    reach, for example. In scene coordinates (mm)."""

    start_mm: tuple[float, float, float]
    end_mm: tuple[float, float, float]
    radius_mm: float
    edge_mm: float


@dataclass(frozen=True)
class BuildSettings:
    """How finely to model the scene; lengths in mm, None: derived from the regions.

    accuracy_mm: how far the scene's surfaces may lie from the input surfaces (default 0.5% of
    the regions' bounding-box diagonal). 40% of it may go to simplifying the input surfaces
    (``simplify``), 40% is fTetWild's envelope (80% without simplifying).
    edge_near_mm: target tet edge length at region surfaces (default: the simplified surfaces'
    mean edge length); edge_far_mm: far from them (default 4x near); the length grows by
    ``grading`` mm per mm of distance in between. adaptive=False: edge_near_mm everywhere.
    """

    enclosure: str = "box"  # "box" (tight), "cube" (the paper's) or "tetrahedron" (4 faces).
    margin_mm: float | None = None  # Gap between the regions and the enclosure (default 25%).
    accuracy_mm: float | None = None
    edge_near_mm: float | None = None
    edge_far_mm: float | None = None
    grading: float = 0.5
    adaptive: bool = True
    simplify: bool = True  # Simplify the input surfaces within the accuracy first.
    coarsen: bool = False  # fTetWild's coarsening: fewer tets, slower.
    refine: tuple[RefineZone, ...] = ()
    max_hole_edges: int = 100  # Holes with up to this many boundary edges are closed.
    air: Material = field(default_factory=lambda: Material("air", "free"))
    measure_deviation: bool = True  # Hausdorff distance of output to input surfaces.
    threads: int = 0  # fTetWild threads; 0: all cores.
    in_subprocess: bool | None = None  # fTetWild in a killable child (None: with a callback).

    def checked(self) -> BuildSettings:
        if self.enclosure not in ENCLOSURES:
            raise BuildError(
                "", f"settings.enclosure: {self.enclosure!r} is not one of {ENCLOSURES}"
            )
        for name in ("margin_mm", "accuracy_mm", "edge_near_mm", "edge_far_mm"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 0):
                raise BuildError("", f"settings.{name}: must be a positive number, not {value}")
        if not (math.isfinite(self.grading) and self.grading > 0):
            raise BuildError("", f"settings.grading: must be a positive number, not {self.grading}")
        if self.air.model != "free":
            raise BuildError("", f"settings.air: the air must be free, not {self.air.model!r}")
        return self


class _Progress:
    """Maps each step's own 0..1 onto the whole build and turns False into BuildCancelled."""

    # Step name -> share of the whole build (fTetWild dominates).
    WEIGHTS = {
        "repair": 0.06,
        "simplify": 0.10,
        "check": 0.04,
        "sizing": 0.04,
        "tetrahedralize": 0.50,
        "label": 0.16,
        "report": 0.10,
    }

    def __init__(self, callback: ProgressCallback | None) -> None:
        self.callback = callback
        self.start = 0.0
        self.step = ""
        self.timings: dict[str, float] = {}
        self.repeating = False  # Steps run again (again()): their weight is already counted.
        self.reached = 0.0  # The last fraction reported.
        self._clock = time.perf_counter()

    def begin(self, step: str, message: str) -> None:
        now = time.perf_counter()
        if self.step:
            self.timings[self.step] = round(self.timings.get(self.step, 0.0) + now - self._clock, 3)
            if not self.repeating:
                self.start += self.WEIGHTS[self.step]
        self.step, self._clock = step, now
        self(0.0, message)

    def again(self, message: str) -> None:
        """The meshing steps are run once more: the progress holds where it got to (it never
        goes back) and the messages say why; their time adds to the same steps."""
        self.repeating, self.start = True, self.reached
        self.begin("", message)

    def finish(self) -> None:
        if self.step:
            self.timings[self.step] = round(
                self.timings.get(self.step, 0.0) + time.perf_counter() - self._clock, 3
            )
        self.step = ""
        if self.callback is not None and self.callback(1.0, "done") is False:
            raise BuildCancelled("cancelled at the end of the build")

    def __call__(self, fraction: float, message: str) -> None:
        if self.callback is None:
            return
        weight = 0.0 if self.repeating else self.WEIGHTS.get(self.step, 0.0)
        self.reached = min(self.start + weight * min(max(fraction, 0.0), 1.0), 1.0)
        if self.callback(self.reached, message) is False:
            raise BuildCancelled(f"cancelled while {message}")


def _materials(regions: Sequence[Region], air: Material) -> list[Material]:
    materials = [air]
    for region in regions:
        known = next((m for m in materials if m.name == region.material.name), None)
        if known is None:
            materials.append(region.material)
        elif known != region.material:
            raise BuildError(
                region.name,
                f"material {region.material.name!r} is given twice with different parameters "
                f"({asdict(known)} and {asdict(region.material)})",
            )
    return materials


def _check_no_crossings(
    names: list[str], surfaces: list[Surface], envelope_mm: float, progress
) -> dict:
    """BuildError when two regions' surfaces cross or come closer than the envelope."""
    crossing = self_intersecting_faces(surfaces)
    owner = np.repeat(np.arange(len(surfaces)), [len(s.faces) for s in surfaces])
    own = np.concatenate([self_intersecting_faces([s]) for s in surfaces])
    self_crossing = {names[r]: int((own & (owner == r)).sum()) for r in range(len(surfaces))}
    progress(0.5, "checking that regions do not cross")
    between = crossing & ~own
    if between.any():
        first = int(owner[np.argmax(between)])
        others = [
            names[r]
            for r in range(len(surfaces))
            if r != first and self_intersecting_faces([surfaces[first], surfaces[r]]).any()
        ]
        partner = others[0] if others else "another region"
        raise BuildError(
            names[first],
            f"its surface crosses region {partner!r} ({int(between.sum())} faces cross); "
            "regions must be nested or apart",
        )
    for r, surface in enumerate(surfaces):
        others = [s for q, s in enumerate(surfaces) if q != r]
        if not others:
            break
        gap = distance_to_surfaces(surface.vertices, others, 2 * envelope_mm)
        if gap.min() < envelope_mm:
            near = min(
                (q for q in range(len(surfaces)) if q != r),
                key=lambda q: distance_to_surfaces(
                    surface.vertices, [surfaces[q]], 2 * envelope_mm
                ).min(),
            )
            raise BuildError(
                names[r],
                f"comes within {gap.min():.3g} mm of region {names[near]!r}, closer than the "
                f"meshing envelope ({envelope_mm:.3g} mm, 40% of accuracy_mm): the layer "
                "between them cannot be resolved; lower accuracy_mm",
            )
    return {name: count for name, count in self_crossing.items() if count}


def _nesting(names: list[str], surfaces: list[Surface], volumes: np.ndarray) -> dict[str, str]:
    """Each region's direct parent ("" for none), from winding numbers of a vertex."""
    parents = {}
    for r, surface in enumerate(surfaces):
        probe = surface.vertices[:1]
        holders = [
            q
            for q, other in enumerate(surfaces)
            if q != r and winding_numbers(probe, other.vertices, other.faces)[0] > INSIDE_WINDING
        ]
        parent = min(holders, key=lambda q: volumes[q]) if holders else None
        parents[names[r]] = names[parent] if parent is not None else ""
    return parents


def _sizing_field(
    enclosure: Surface,
    surfaces: list[Surface],
    near_mm: float,
    far_mm: float,
    grading: float,
    refine: Iterable[RefineZone],
):
    """Background tets over the enclosure's box with a target edge length per vertex."""
    low, high = enclosure.vertices.min(axis=0), enclosure.vertices.max(axis=0)
    extent = high - low
    cell = max(near_mm, float(extent.max()) / SIZING_GRID_CELLS)
    cells = tuple(int(max(1, math.ceil(e / cell))) for e in extent)
    vertices, tets = kuhn_grid(low, high, cells)
    reach = (far_mm - near_mm) / grading
    distance = distance_to_surfaces(vertices, surfaces, max(reach, cell))
    values = np.clip(near_mm + grading * distance, near_mm, far_mm)
    for zone in refine:
        gap = np.maximum(
            point_segment_distance(vertices, zone.start_mm, zone.end_mm) - zone.radius_mm, 0
        )
        values = np.minimum(values, zone.edge_mm + grading * gap)
    return vertices, tets, values


def _check_boundary(vertices, tets, enclosure: Surface, envelope_mm: float, size: float) -> dict:
    """The mesh's boundary must be the enclosure, to within fTetWild's envelope.

    fTetWild may move any input surface within its envelope, the enclosure's included: with a
    coarse accuracy it can bevel the enclosure's corners and edges by up to the envelope.
    """
    normals, offsets = enclosure_planes(enclosure.vertices, enclosure.faces)
    outer = boundary_faces(tets)
    used, compact = np.unique(outer, return_inverse=True)
    distance = np.abs(vertices[used] @ normals.T - offsets)  # (b, planes)
    # A face is on the enclosure when all three corners lie on one of its planes.
    on_one_plane = np.any(np.all(distance[compact.reshape(-1, 3)] < 1e-9 * size, axis=1), axis=1)
    area = float(triangle_areas(vertices, outer).sum())
    enclosure_area = float(triangle_areas(enclosure.vertices, enclosure.faces).sum())
    deviation = surface_deviation(enclosure, Surface(vertices[used], compact.reshape(-1, 3)))
    result = {
        "boundary_faces": int(len(outer)),
        "boundary_faces_off_enclosure_planes": int((~on_one_plane).sum()),
        "boundary_deviation_mm": round(deviation, 6),
        "boundary_area_relative_error": float(abs(area - enclosure_area) / enclosure_area),
    }
    if deviation > 1.5 * envelope_mm + 1e-9 * size:
        raise BuildError(
            "",
            f"the tet mesh's boundary is not the enclosure: it lies up to {deviation:.3g} mm from "
            f"it, beyond the meshing envelope ({envelope_mm:.3g} mm); report this input",
        )
    return result


@dataclass(frozen=True)
class Lengths:
    """The build's lengths in mm, from the settings or derived from the regions' size."""

    low_mm: np.ndarray  # The repaired regions' bounding box.
    high_mm: np.ndarray
    size_mm: float  # Its diagonal.
    accuracy_mm: float
    envelope_mm: float  # fTetWild's envelope.


def build(
    regions: Sequence[Region],
    blades: Iterable[BladeSpec] = (),
    settings: BuildSettings | None = None,
    progress: ProgressCallback | None = None,
) -> Scene:
    """The labelled tet scene of the regions and the air around them (see the module doc).

    progress(fraction, message) is called often; returning False cancels (BuildCancelled).
    Raises BuildError naming the region and the problem for input it cannot use.
    """
    settings = (settings or BuildSettings()).checked()
    regions = list(regions)
    materials = _check_regions(regions, settings)
    steps = _Progress(progress)
    report = BuildReport(tetwild=f"pytetwild {tetwild.version()}")
    repaired = _repair(regions, settings, steps, report)
    lengths = _lengths(repaired, settings)
    surfaces = _simplify(regions, repaired, lengths, settings, steps, report)
    volumes = _check_layout(regions, surfaces, lengths, steps, report)
    enclosure, sizing, edge_mm = _enclose_and_size(surfaces, lengths, settings, steps, report)
    in_subprocess = (
        settings.in_subprocess if settings.in_subprocess is not None else progress is not None
    )
    for attempt in range(1, MESHING_ATTEMPTS + 1):
        vertices, tets = _tetrahedralize(
            enclosure, surfaces, sizing, edge_mm, lengths, settings, in_subprocess, steps, report
        )
        inside, tet_materials = _label(
            vertices, tets, regions, surfaces, volumes, materials, lengths, steps, report
        )
        _measure_deviation(vertices, tets, inside, regions, repaired, settings, steps, report)
        if _accurate_enough(lengths, attempt, report):
            break
        # The meshed surface strays by the simplification, fTetWild's envelope and the
        # labelling together, and fTetWild's output differs between runs: beyond the accuracy,
        # mesh again with half the envelope.
        lengths = replace(lengths, envelope_mm=lengths.envelope_mm / 2)
        report.settings["envelope_mm"] = round(lengths.envelope_mm, 6)
        steps.again(f"meshing again with a {lengths.envelope_mm:.3g} mm envelope")
    # Quality and valence of the mesh kept only, not of the meshings made again.
    steps(0.5, "measuring quality")
    report.mesh = mesh_report(vertices, tets, tet_materials, [m.name for m in materials])
    steps.finish()
    report.timings_s = dict(steps.timings)
    report.timings_s["total"] = round(sum(steps.timings.values()), 3)
    # Stored near in space, near in memory (locality.py): the engine's walks then miss less.
    vertices, tets, tet_materials = in_locality_order(vertices, tets, tet_materials)
    return Scene(
        materials=materials,
        vertices=vertices,
        tets=tets,
        tet_materials=tet_materials,
        blades=list(blades),
        metadata={"build_report": report.as_json()},
    )


def _check_regions(regions: list[Region], settings: BuildSettings) -> list[Material]:
    """The scene's materials (the air first); BuildError for no regions or a repeated name."""
    if not regions:
        raise BuildError("", "no regions to build a scene from")
    names = [region.name for region in regions]
    duplicates = sorted({n for n in names if names.count(n) > 1})
    if duplicates:
        raise BuildError(duplicates[0], "two regions have this name")
    return _materials(regions, settings.air)


def _repair(
    regions: list[Region], settings: BuildSettings, steps: _Progress, report: BuildReport
) -> list[Surface]:
    steps.begin("repair", "repairing surfaces")
    repaired: list[Surface] = []
    for i, region in enumerate(regions):
        surface, repairs = repair_surface(
            region.name, region.vertices, region.faces, settings.max_hole_edges
        )
        repaired.append(surface)
        report.repairs[region.name] = repairs
        steps((i + 1) / len(regions), f"repaired {region.name}")
    return repaired


def _lengths(repaired: list[Surface], settings: BuildSettings) -> Lengths:
    all_vertices = np.concatenate([s.vertices for s in repaired])
    low, high = all_vertices.min(axis=0), all_vertices.max(axis=0)
    size = float(np.linalg.norm(high - low))
    accuracy = settings.accuracy_mm or DEFAULT_ACCURACY_RATIO * size
    envelope = accuracy * ENVELOPE_SHARE if settings.simplify else accuracy * 0.8
    return Lengths(low, high, size, accuracy, envelope)


def _simplify(
    regions: list[Region],
    repaired: list[Surface],
    lengths: Lengths,
    settings: BuildSettings,
    steps: _Progress,
    report: BuildReport,
) -> list[Surface]:
    steps.begin("simplify", "simplifying surfaces")
    surfaces: list[Surface] = []
    for i, (region, surface) in enumerate(zip(regions, repaired, strict=True)):
        if settings.simplify:
            simple, before, deviation = simplify_surface(
                surface,
                lengths.accuracy_mm * SIMPLIFY_SHARE,
                on_attempt=lambda f, i=i, n=region.name: steps(
                    (i + f) / len(regions), f"simplifying {n}"
                ),
            )
        else:
            simple, before, deviation = surface, len(surface.faces), 0.0
        surfaces.append(simple)
        report.surfaces[region.name] = SurfaceReport(
            faces_in=int(before),
            faces_meshed=int(len(simple.faces)),
            simplification_deviation_mm=round(float(deviation), 6),
        )
        steps((i + 1) / len(regions), f"simplified {region.name}")
    return surfaces


def _check_layout(
    regions: list[Region],
    surfaces: list[Surface],
    lengths: Lengths,
    steps: _Progress,
    report: BuildReport,
) -> np.ndarray:
    """BuildError unless regions are nested or apart; each region's volume (mm^3)."""
    steps.begin("check", "checking that regions do not cross")
    names = [region.name for region in regions]
    report.self_intersecting_faces = _check_no_crossings(
        names, surfaces, lengths.envelope_mm, steps
    )
    volumes = np.array([signed_volume(s.vertices, s.faces) for s in surfaces])
    report.nesting = _nesting(names, surfaces, volumes)
    for name, volume in zip(names, volumes, strict=True):
        report.surfaces[name].volume_mm3 = round(float(volume), 3)
    return volumes


def _enclose_and_size(
    surfaces: list[Surface],
    lengths: Lengths,
    settings: BuildSettings,
    steps: _Progress,
    report: BuildReport,
) -> tuple[Surface, tuple | None, float]:
    """The enclosure, the sizing field (None: uniform) and fTetWild's edge length."""
    steps.begin("sizing", "sizing field")
    extent = float((lengths.high_mm - lengths.low_mm).max())
    margin = settings.margin_mm or DEFAULT_MARGIN_RATIO * extent
    enclosure = Surface(
        *enclosure_surface(settings.enclosure, lengths.low_mm, lengths.high_mm, margin)
    )
    edges = np.concatenate(
        [
            np.linalg.norm(
                s.vertices[s.faces] - s.vertices[np.roll(s.faces, 1, axis=1)], axis=2
            ).ravel()
            for s in surfaces
        ]
    )
    near = settings.edge_near_mm or float(edges.mean())
    far = max(settings.edge_far_mm or DEFAULT_FAR_RATIO * near, near)
    sizing = None
    if settings.adaptive and (far > near or settings.refine):
        sizing = _sizing_field(enclosure, surfaces, near, far, settings.grading, settings.refine)
    edge_mm = far if sizing is not None else near
    report.settings = {
        "enclosure": settings.enclosure,
        "margin_mm": round(margin, 6),
        "accuracy_mm": round(lengths.accuracy_mm, 6),
        "envelope_mm": round(lengths.envelope_mm, 6),
        "edge_near_mm": round(near, 6),
        "edge_far_mm": round(edge_mm, 6),
        "grading": settings.grading,
        "adaptive": sizing is not None,
        "simplify": settings.simplify,
        "coarsen": settings.coarsen,
        "refine_zones": [asdict(zone) for zone in settings.refine],
        "max_hole_edges": settings.max_hole_edges,
    }
    report.enclosure = {
        "kind": settings.enclosure,
        "low_mm": enclosure.vertices.min(axis=0).round(6).tolist(),
        "high_mm": enclosure.vertices.max(axis=0).round(6).tolist(),
        "faces": int(len(enclosure.faces)),
    }
    return enclosure, sizing, edge_mm


def _tetrahedralize(
    enclosure: Surface,
    surfaces: list[Surface],
    sizing: tuple | None,
    edge_mm: float,
    lengths: Lengths,
    settings: BuildSettings,
    in_subprocess: bool,
    steps: _Progress,
    report: BuildReport,
) -> tuple[np.ndarray, np.ndarray]:
    """One conforming tet mesh of the enclosure and every region surface (fTetWild), its
    unused vertices dropped and every tet positively oriented."""
    steps.begin("tetrahedralize", "tetrahedralizing (fTetWild)")
    pieces = [enclosure, *surfaces]
    offsets = np.cumsum([0] + [len(p.vertices) for p in pieces[:-1]])
    input_vertices = np.concatenate([p.vertices for p in pieces])
    input_faces = np.concatenate([p.faces + o for p, o in zip(pieces, offsets, strict=True)])
    params = tetwild.TetWildParams(
        edge_length_mm=edge_mm,
        envelope_mm=lengths.envelope_mm,
        simplify=settings.simplify,
        coarsen=settings.coarsen,
        threads=settings.threads,
    )

    def poll(elapsed_s: float) -> None:
        # fTetWild reports nothing while it runs: creep towards the end of its share.
        steps(1 - 1 / (1 + elapsed_s / 10), f"tetrahedralizing (fTetWild, {elapsed_s:.0f} s)")

    try:
        vertices, tets = tetwild.tetrahedralize(
            input_vertices, input_faces, params, sizing, poll=poll if in_subprocess else None
        )
    except RuntimeError as error:
        raise BuildError("", f"tetrahedralization failed: {error}") from None
    if len(tets) == 0:
        raise BuildError("", "fTetWild returned no tets")
    used = np.unique(tets)
    if len(used) != len(vertices):
        remap = np.full(len(vertices), -1)
        remap[used] = np.arange(len(used))
        vertices, tets = vertices[used], remap[tets]
    tets = orient_tets(vertices, tets)
    report.boundary = _check_boundary(
        vertices, tets, enclosure, lengths.envelope_mm, lengths.size_mm
    )
    return vertices, tets


def _label(
    vertices: np.ndarray,
    tets: np.ndarray,
    regions: list[Region],
    surfaces: list[Surface],
    volumes: np.ndarray,
    materials: list[Material],
    lengths: Lengths,
    steps: _Progress,
    report: BuildReport,
) -> tuple[np.ndarray, np.ndarray]:
    """Which regions hold each tet ((regions, tets) bool) and each tet's material index."""
    steps.begin("label", "labelling tets")
    inside, label_stats = containment(
        vertices, tets, surfaces, lengths.envelope_mm, lambda f: steps(f, "labelling tets")
    )
    holder = innermost(inside, volumes)
    material_index = {m.name: i for i, m in enumerate(materials)}
    region_material = np.array([material_index[r.material.name] for r in regions])
    tet_materials = np.where(holder >= 0, region_material[np.maximum(holder, 0)], 0).astype(
        np.int32
    )
    report.labels = label_stats
    report.tets_per_region = {r.name: int((holder == i).sum()) for i, r in enumerate(regions)}
    report.tets_per_region["(air)"] = int((holder < 0).sum())
    return inside, tet_materials


def _measure_deviation(
    vertices: np.ndarray,
    tets: np.ndarray,
    inside: np.ndarray,
    regions: list[Region],
    repaired: list[Surface],
    settings: BuildSettings,
    steps: _Progress,
    report: BuildReport,
) -> None:
    """Each region's meshed surface's deviation from its input (when measured)."""
    steps.begin("report", "measuring surface deviation")
    if not settings.measure_deviation:
        return
    report.deviation_mm = {}
    for r, region in enumerate(regions):
        faces = interface_faces(tets, inside[r])
        if len(faces) == 0:
            raise BuildError(region.name, "no tet lies inside this region after meshing")
        used, compact = np.unique(faces, return_inverse=True)
        meshed = Surface(vertices[used], compact.reshape(-1, 3))
        report.deviation_mm[region.name] = round(surface_deviation(repaired[r], meshed), 6)
        steps(0.5 * (r + 1) / len(regions), "measuring surface deviation")


def _accurate_enough(lengths: Lengths, attempt: int, report: BuildReport) -> bool:
    """Whether every region's meshed surface lies within accuracy_mm of its input (always
    true unmeasured). The attempt is listed in the report; BuildError after the last one."""
    if report.deviation_mm is None:
        return True
    worst = max(report.deviation_mm, key=report.deviation_mm.get)
    report.meshing_attempts.append(
        {"envelope_mm": round(lengths.envelope_mm, 6), "deviation_mm": dict(report.deviation_mm)}
    )
    deviation = report.deviation_mm[worst]
    if deviation <= lengths.accuracy_mm:
        return True
    if attempt == MESHING_ATTEMPTS:
        meshings = f"{attempt} meshing" + ("s" if attempt > 1 else "")
        raise BuildError(
            worst,
            f"its meshed surface lies up to {deviation:.3g} mm from the input surface, beyond "
            f"accuracy_mm ({lengths.accuracy_mm:.3g} mm), after {meshings} down to a "
            f"{lengths.envelope_mm:.3g} mm envelope; raise accuracy_mm or report this input",
        )
    return False
