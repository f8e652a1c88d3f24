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

from ..scenefile.format import materials_problem
from ..scenefile.model import MODEL_PARAMETERS, BladeSpec, Material, Scene
from . import tetwild
from .errors import BuildCancelled, BuildError
from .geometry import (
    Surface,
    boundary_faces,
    buried_faces,
    enclosure_planes,
    enclosure_surface,
    face_normals,
    interface_faces,
    kuhn_grid,
    orient_tets,
    point_segment_distance,
    ray_hit_distances,
    signed_volume,
    triangle_areas,
    winding_numbers,
)
from .labels import INSIDE_WINDING, components, containment, innermost
from .locality import in_locality_order
from .quality import mesh_report
from .repair import (
    distance_to_surfaces,
    one_sided_deviation,
    read_surface,
    repair_surface,
    self_intersecting_faces,
    surface_deviation,
)
from .report import BuildReport, SurfaceReport, figures_apart
from .simplify import simplify_surface

__all__ = [
    "BuildCancelled",
    "BuildError",
    "BuildReport",
    "BuildSettings",
    "ProgressCallback",
    "RefineZone",
    "Region",
    "build",
    "check_layout",
    "cut_variant",
    "units_warning",
]

ENCLOSURES = ("box", "cube", "tetrahedron")
# progress(fraction 0..1, message) -> False to cancel (None or True: go on). A callback that
# also has on_step(step, meshing, meshings) is told each step as it begins ("repair", ...,
# "report", then "done") and which meshing it belongs to (2 of 3 when meshing again).
ProgressCallback = Callable[[float, str], "bool | None"]
# Defaults relative to the regions' size (their bounding box): see BuildSettings.
# The air is modelled only as far as the scene needs it, so most tets are not air: a margin
# of 5% of the regions' largest extent, but at least two tet edges at the surfaces; in the
# air the tets grow six times as fast as inside the regions, up to three times the far edge.
DEFAULT_MARGIN_RATIO = 0.05
MARGIN_NEAR_EDGES = 2.0
DEFAULT_AIR_GRADING = 3.0
AIR_FAR_RATIO = 3.0
# 1% of the diagonal (about 1.5 mm on a 100 mm scan): a default build of a single scan stays
# well under a minute; a finer accuracy is one setting away.
DEFAULT_ACCURACY_RATIO = 0.01
DEFAULT_FAR_RATIO = 4.0
# The background grid of the sizing field: at most this many cells along the longest side.
SIZING_GRID_CELLS = 32
# fTetWild's edge length where the sizing field does not reach, as a share of the enclosure's
# largest side at most. fTetWild grows the box it meshes by that length on every side and
# fills the grown box with points (about 15 along the input's diagonal) that it then
# coarsens: a length near the enclosure's size (a small scene, whose far edges follow its
# size) fills many times the enclosure's volume with points coarsened for seconds, and
# dropped at the end with everything outside the enclosure. Inside the enclosure the sizing
# field still rules: a quarter leaves about as many tets, the far air's a little finer
# (docs/decisions.md, "fTetWild's outer edge length").
OUTER_EDGE_SHARE = 0.25
# Shares of accuracy_mm: simplifying the input, and fTetWild's envelope. fTetWild keeps its
# output within the envelope of its input but not the converse, so a fifth is held back.
SIMPLIFY_SHARE = 0.4
ENVELOPE_SHARE = 0.4
# How often the tet mesh is made, halving the envelope each time, until every region's meshed
# surface lies within accuracy_mm of its input (when measure_deviation is on).
MESHING_ATTEMPTS = 3
# A feature lost at one meshing (a part thinner, or a gap narrower, than the tets there) is
# meshed again with edges of this share of its width, never below this share of
# edge_near_mm: finer tets make fTetWild minutes slower. A feature narrower than that, or
# than twice the envelope (fTetWild merges surfaces closer than it), is reported, not chased.
LOST_FEATURE_EDGE_SHARE = 0.5
LOST_FEATURE_MIN_EDGE_SHARE = 0.25
# Faces at least this share of the deepest face's distance count as lost when none is beyond
# the accuracy at its corners and centre.
LOST_FACE_SHARE = 0.8
# Lost features named in the report per region, and refine zones per feature.
LOST_FEATURES_LISTED = 5
ZONES_PER_LOST_FEATURE = 40
# The name of a material's weaker cut variant (cut_variant): the material's, then this.
CUT_VARIANT_SUFFIX = "_cut"
# An input smaller or larger than this across is most likely in other units than mm.
UNITS_MIN_MM = 5.0
UNITS_MAX_MM = 5000.0


@dataclass(frozen=True, eq=False)
class Region:
    """A closed surface mesh filled with one material (vertices (n, 3) mm, faces (f, 3)).

    ``cut_material``: the material ``material.cut_to`` names when no region is filled with it
    (a weaker copy, cut_variant): the scene's table holds it after the regions' materials. A
    cut_to naming the air or another region's material needs none.
    """

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    material: Material
    cut_material: Material | None = None

    @classmethod
    def from_file(
        cls,
        path: str | os.PathLike,
        material: Material,
        name: str | None = None,
        scale: float = 1.0,
        cut_material: Material | None = None,
    ) -> Region:
        """A region read from a mesh file (OBJ, PLY, STL, OFF...), named after the file."""
        if name is None:
            name = os.path.basename(os.fspath(path)).split(".")[0]
        try:
            vertices, faces = read_surface(path)
        except BuildError as error:
            raise BuildError(name, error.problem) from None
        vertices = np.asarray(vertices, np.float64) * scale
        return cls(name, vertices, np.asarray(faces), material, cut_material)


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

    accuracy_mm: how far the scene's surfaces may lie from the input surfaces (default 1% of
    the regions' bounding-box diagonal); held by meshing again (up to MESHING_ATTEMPTS), and
    where it cannot be, reported (or a BuildError with strict_accuracy). 40% of it may go to
    simplifying the input surfaces (``simplify``), 40% is fTetWild's envelope (80% without
    simplifying).
    edge_near_mm: target tet edge length at region surfaces (default: the simplified surfaces'
    mean edge length); edge_far_mm: far from them (default 4x near); the length grows by
    ``grading`` mm per mm of distance in between inside the regions, ``air_grading`` outside
    them (the air). adaptive=False: edge_near_mm everywhere.
    """

    enclosure: str = "box"  # "box" (tight), "cube" (the paper's) or "tetrahedron" (4 faces).
    margin_mm: float | None = None  # Regions to enclosure (default: 5% of the extent).
    accuracy_mm: float | None = None
    edge_near_mm: float | None = None
    edge_far_mm: float | None = None
    grading: float = 0.5
    air_grading: float = DEFAULT_AIR_GRADING  # Edge growth per mm outside every region.
    adaptive: bool = True
    simplify: bool = True  # Simplify the input surfaces within the accuracy first.
    # fTetWild's coarsening: it removes mostly air tets at little cost, so the air stays a
    # minority of the tets.
    coarsen: bool = True
    refine: tuple[RefineZone, ...] = ()
    max_hole_edges: int = 100  # Holes with up to this many boundary edges are closed.
    air: Material = field(default_factory=lambda: Material("air", "free"))
    measure_deviation: bool = True  # Hausdorff distance of output to input surfaces.
    # True: BuildError when a region's meshed surface is still beyond accuracy_mm after
    # MESHING_ATTEMPTS meshings. False: keep the best meshing and say in the report where
    # the accuracy was not held (``accuracy_not_held``).
    strict_accuracy: bool = False
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
        for name in ("grading", "air_grading"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise BuildError("", f"settings.{name}: must be a positive number, not {value}")
        if self.air.model != "free":
            raise BuildError("", f"settings.air: the air must be free, not {self.air.model!r}")
        return self


class _Progress:
    """Maps each step's own 0..1 onto the whole run (the build, or only the given steps of
    it) and turns False into BuildCancelled."""

    # Step name -> share of the whole build, as the steps' times share a default build of a
    # scan (fTetWild dominates; Check Scene's steps are simplifying, mostly: checking the
    # simplified surfaces takes about a hundredth of it, so its share is small, or Check
    # Scene's bar would jump by a tenth at its end).
    WEIGHTS = {
        "repair": 0.01,
        "simplify": 0.08,
        "check": 0.002,
        "sizing": 0.06,
        "tetrahedralize": 0.78,
        "label": 0.04,
        "report": 0.02,
    }

    def __init__(self, callback: ProgressCallback | None, steps: Sequence[str] = ()) -> None:
        self.callback = callback
        chosen = steps or tuple(self.WEIGHTS)
        total = sum(self.WEIGHTS[step] for step in chosen)
        self.weights = {step: self.WEIGHTS[step] / total for step in chosen}
        self.on_step = getattr(callback, "on_step", None)
        self.meshing = 1  # Which meshing the steps belong to (again() counts up).
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
                self.start += self.weights[self.step]
        self.step, self._clock = step, now
        if self.on_step is not None:
            self.on_step(step, self.meshing, MESHING_ATTEMPTS)
        self(0.0, message)

    def again(self, message: str) -> None:
        """The meshing steps are run once more: the progress holds where it got to (it never
        goes back), the steps say which meshing they belong to and the message says why;
        their time adds to the same steps."""
        self.repeating, self.start = True, self.reached
        self.meshing += 1
        self.begin("tetrahedralize", message)

    def finish(self) -> None:
        if self.step:
            self.timings[self.step] = round(
                self.timings.get(self.step, 0.0) + time.perf_counter() - self._clock, 3
            )
        self.step = ""
        if self.on_step is not None:
            self.on_step("done", self.meshing, MESHING_ATTEMPTS)
        if self.callback is not None and self.callback(1.0, "done") is False:
            raise BuildCancelled("cancelled at the end of the build")

    def __call__(self, fraction: float, message: str) -> None:
        if self.callback is None:
            return
        weight = 0.0 if self.repeating else self.weights.get(self.step, 0.0)
        self.reached = min(self.start + weight * min(max(fraction, 0.0), 1.0), 1.0)
        if self.callback(self.reached, message) is False:
            raise BuildCancelled(f"cancelled while {message}")


def cut_variant(material: Material, factor: float) -> Material:
    """A weaker copy of ``material`` for its tets once cut, named ``<name>_cut``: the same
    model, every parameter of it times ``factor`` (a drag's distance, a viscous material's
    viscosity and lag cap, a membrane's break force), so the force it can push back with
    scales by the factor. The material names it in its ``cut_to`` (docs/scene-format.md)."""
    scaled = {name: getattr(material, name) * factor for name in MODEL_PARAMETERS[material.model]}
    return replace(material, name=material.name + CUT_VARIANT_SUFFIX, cut_to="", **scaled)


def _materials(regions: Sequence[Region], air: Material) -> list[Material]:
    """The scene's material table: the air, each region's material, then the cut variants no
    region is filled with. BuildError, naming the region, for one name given to different
    materials, or for a table the scene file would refuse (a parameter out of range, a cut_to
    naming no material, a rigid one, or making a cycle: the scene writer's own checks)."""
    materials = [air]
    variant_of: dict[str, str] = {}  # A cut variant's name -> its material's.
    entries = [(region, region.material, "") for region in regions]
    entries += [(r, r.cut_material, r.material.name) for r in regions if r.cut_material is not None]
    for region, material, source in entries:
        known = next((m for m in materials if m.name == material.name), None)
        if known is None:
            materials.append(material)
            if source:
                variant_of[material.name] = source
        elif known != material and source and variant_of.get(material.name) != source:
            raise BuildError(
                region.name,
                f"the cut variant of material {source!r} would be named {material.name!r}, "
                "which another material has: rename that material",
            )
        elif known != material:
            what = (
                f"material {source!r} is given two different cut variants"
                if source
                else f"material {material.name!r} is given twice with different parameters"
            )
            raise BuildError(region.name, f"{what} ({asdict(known)} and {asdict(material)})")
    problem = materials_problem(materials)
    if problem is not None:
        name = materials[int(problem.field.split("/")[2])].name
        owner = next((r.name for r, m, _ in entries if m.name == name), "")
        raise BuildError(owner, problem.reason)
    return materials


def _check_no_crossings(
    names: list[str], surfaces: list[Surface], envelope_mm: float, progress
) -> dict:
    """BuildError when two regions' surfaces cross or come closer than the envelope (a
    region touching another, or a copy of it in the same place)."""
    count = len(surfaces)
    progress(0.0, f"checking that regions do not cross ({_faces_text(surfaces)})")
    crossing = self_intersecting_faces(surfaces)
    owner = np.repeat(np.arange(count), [len(s.faces) for s in surfaces])
    own_parts = []
    for r, surface in enumerate(surfaces):
        progress(0.2 + 0.2 * r / count, f"checking {names[r]} ({_faces_text([surface])})")
        own_parts.append(self_intersecting_faces([surface]))
    own = np.concatenate(own_parts)
    self_crossing = {names[r]: int((own & (owner == r)).sum()) for r in range(count)}
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
        progress(0.4 + 0.6 * r / count, f"checking how near {names[r]} comes to the others")
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


def _faces_text(surfaces: list[Surface]) -> str:
    faces = sum(len(s.faces) for s in surfaces)
    return f"{faces:,} face" + ("s" if faces != 1 else "")


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
    air_grading: float | None = None,
    air_far_mm: float | None = None,
):
    """Background tets over the enclosure's box with a target edge length per vertex:
    near_mm at the surfaces, growing by ``grading`` mm per mm inside the regions up to
    far_mm, and by ``air_grading`` outside them up to air_far_mm (default: as inside)."""
    air_grading = air_grading or grading
    air_far_mm = air_far_mm or far_mm
    low, high = enclosure.vertices.min(axis=0), enclosure.vertices.max(axis=0)
    extent = high - low
    cell = max(near_mm, float(extent.max()) / SIZING_GRID_CELLS)
    cells = tuple(int(max(1, math.ceil(e / cell))) for e in extent)
    vertices, tets = kuhn_grid(low, high, cells)
    reach = max((far_mm - near_mm) / grading, (air_far_mm - near_mm) / air_grading)
    distance = distance_to_surfaces(vertices, surfaces, max(reach, cell))
    values = np.clip(near_mm + grading * distance, near_mm, far_mm)
    if air_grading != grading or air_far_mm != far_mm:
        inside = np.zeros(len(vertices), dtype=bool)
        for surface in surfaces:
            inside |= winding_numbers(vertices, surface.vertices, surface.faces) > INSIDE_WINDING
        in_air = np.clip(near_mm + air_grading * distance, near_mm, air_far_mm)
        values = np.where(inside, values, in_air)
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
    steps = _Progress(progress)
    report = BuildReport(tetwild=f"pytetwild {tetwild.version()}")
    materials, repaired, lengths, surfaces, volumes = _prepare(regions, settings, steps, report)
    enclosure, sizing, edge_mm = _enclose_and_size(surfaces, lengths, settings, steps, report)
    in_subprocess = (
        settings.in_subprocess if settings.in_subprocess is not None else progress is not None
    )
    refine: tuple[RefineZone, ...] = ()
    meshings: list[_Meshing] = []
    for attempt in range(1, MESHING_ATTEMPTS + 1):
        if refine:
            sizing, edge_mm = _size(enclosure, surfaces, settings, refine, report)
        vertices, tets = _tetrahedralize(
            enclosure, surfaces, sizing, edge_mm, lengths, settings, in_subprocess, steps, report
        )
        inside, tet_materials = _label(
            vertices, tets, regions, surfaces, volumes, materials, lengths, steps, report
        )
        emptied = [r.name for r, held in zip(regions, inside, strict=True) if not held.any()]
        if emptied:
            # fTetWild merged a region's surfaces (it is thinner than twice the envelope here,
            # or this run's output happened to): no meshing without its tets is usable.
            report.meshing_attempts.append(
                {"envelope_mm": round(lengths.envelope_mm, 6), "no_tet_inside": emptied}
            )
            if attempt == MESHING_ATTEMPTS:
                if not meshings:
                    raise _emptied_error(emptied[0], attempt, lengths)
                break  # The best of the earlier meshings is kept.
            lengths = replace(lengths, envelope_mm=lengths.envelope_mm / 2)
            report.settings["envelope_mm"] = round(lengths.envelope_mm, 6)
            steps.again(
                f"meshing again with a {lengths.envelope_mm:.3g} mm envelope: no tet inside "
                f"{emptied[0]} (meshing {attempt + 1} of {MESHING_ATTEMPTS})"
            )
            continue
        misses = _measure_deviation(
            vertices, tets, inside, regions, repaired, lengths, settings, steps, report
        )
        meshings.append(_Meshing(vertices, tets, tet_materials, _meshing_report(report), misses))
        if not misses or attempt == MESHING_ATTEMPTS:
            break
        # Beyond the accuracy. Where the meshed surface strays from the input (fTetWild's
        # envelope, its output differs between runs), mesh again with half the envelope;
        # where the input lies far from the meshed surface (a feature thinner than the tets
        # lost), mesh again with tets finer than the feature there.
        again = []
        zones = _refine_zones(misses, report.settings["edge_near_mm"], lengths.envelope_mm)
        strayed = any(miss.strayed_mm > lengths.accuracy_mm for miss in misses)
        if not zones and not strayed:
            break  # Only features no meshing here can keep: say so, mesh no more.
        if strayed:
            lengths = replace(lengths, envelope_mm=lengths.envelope_mm / 2)
            report.settings["envelope_mm"] = round(lengths.envelope_mm, 6)
            again.append(f"with a {lengths.envelope_mm:.3g} mm envelope")
        if zones:
            refine = (*refine, *zones)
            spots = sum(f.get("meshed_finer", False) for m in misses for f in m.features)
            again.append(f"finer at {spots} lost feature" + ("s" if spots > 1 else ""))
        steps.again(
            f"meshing again {' and '.join(again)} (meshing {attempt + 1} of {MESHING_ATTEMPTS})"
        )
    vertices, tets, tet_materials = _keep_best(meshings, lengths, settings, report)
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


# The steps before meshing: what check_layout runs.
CHECK_STEPS = ("repair", "simplify", "check")


def check_layout(
    regions: Sequence[Region],
    settings: BuildSettings | None = None,
    progress: ProgressCallback | None = None,
) -> BuildReport:
    """The build's checks without the meshing (the add-on's Check Scene): the regions
    repaired, simplified and tested as build() tests them (crossing, touching or lying on one
    another: regions must be nested or apart). Raises BuildError as build() would; the report
    of the steps run (repairs, nesting, volumes)."""
    settings = (settings or BuildSettings()).checked()
    steps = _Progress(progress, CHECK_STEPS)
    report = BuildReport(tetwild="")  # Nothing is meshed.
    _prepare(list(regions), settings, steps, report)
    steps.finish()
    report.timings_s = dict(steps.timings)
    return report


def _prepare(
    regions: list[Region], settings: BuildSettings, steps: _Progress, report: BuildReport
) -> tuple[list[Material], list[Surface], Lengths, list[Surface], np.ndarray]:
    """The steps before meshing, shared by build() and check_layout(): the materials, the
    repaired and the simplified surfaces, the lengths and each region's volume."""
    materials = _check_regions(regions, settings)
    report.warnings = [w for w in (units_warning(r.name, r.vertices) for r in regions) if w]
    repaired = _repair(regions, settings, steps, report)
    lengths = _lengths(repaired, settings)
    surfaces = _simplify(regions, repaired, lengths, settings, steps, report)
    volumes = _check_layout(regions, surfaces, lengths, steps, report)
    return materials, repaired, lengths, surfaces, volumes


def units_warning(name: str, vertices: np.ndarray) -> str | None:
    """A warning when a region is under UNITS_MIN_MM or over UNITS_MAX_MM across (its bounding
    box's largest side): mesh files have no units, so it is most likely not in mm."""
    vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3)
    vertices = vertices[np.isfinite(vertices).all(axis=1)]
    if len(vertices) < 2:
        return None
    across = float(np.ptp(vertices, axis=0).max())
    if UNITS_MIN_MM <= across <= UNITS_MAX_MM or across == 0:
        return None
    to_100 = 100.0 / across
    return (
        f"region {name!r} is {across:.3g} mm across: mesh files have no units, is it in mm? "
        f"Scale it (hapticut mesh --scale {to_100:.3g} makes it 100 mm; --scale 1000 reads "
        "metres, 10 cm, 25.4 inches)"
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
        steps(i / len(regions), f"repairing {region.name} ({len(region.faces):,} faces)")
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
        doing = f"simplifying {region.name} ({len(surface.faces):,} faces)"
        steps(i / len(regions), doing)
        if settings.simplify:
            simple, before, deviation = simplify_surface(
                surface,
                lengths.accuracy_mm * SIMPLIFY_SHARE,
                on_attempt=lambda f, i=i, doing=doing: steps((i + f) / len(regions), doing),
            )
        else:
            simple, before, deviation = surface, len(surface.faces), 0.0
        surfaces.append(simple)
        report.surfaces[region.name] = SurfaceReport(
            faces_in=int(before),
            faces_meshed=int(len(simple.faces)),
            simplification_deviation_mm=round(float(deviation), 6),
        )
        steps(
            (i + 1) / len(regions),
            f"simplified {region.name} ({before:,} to {len(simple.faces):,} faces)",
        )
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
    extent = float((lengths.high_mm - lengths.low_mm).max())
    margin = settings.margin_mm or max(DEFAULT_MARGIN_RATIO * extent, MARGIN_NEAR_EDGES * near)
    enclosure = Surface(
        *enclosure_surface(settings.enclosure, lengths.low_mm, lengths.high_mm, margin)
    )
    report.settings = {
        "enclosure": settings.enclosure,
        "margin_mm": round(margin, 6),
        "accuracy_mm": round(lengths.accuracy_mm, 6),
        "envelope_mm": round(lengths.envelope_mm, 6),
        "edge_near_mm": round(near, 6),
        "edge_far_mm": round(far, 6),
        "grading": settings.grading,
        "air_grading": settings.air_grading,
        "adaptive": settings.adaptive,
        "simplify": settings.simplify,
        "coarsen": settings.coarsen,
        "refine_zones": [asdict(zone) for zone in settings.refine],
        "max_hole_edges": settings.max_hole_edges,
        "strict_accuracy": settings.strict_accuracy,
    }
    report.enclosure = {
        "kind": settings.enclosure,
        "low_mm": enclosure.vertices.min(axis=0).round(6).tolist(),
        "high_mm": enclosure.vertices.max(axis=0).round(6).tolist(),
        "faces": int(len(enclosure.faces)),
    }
    sizing, edge_mm = _size(enclosure, surfaces, settings, (), report)
    return enclosure, sizing, edge_mm


def _size(
    enclosure: Surface,
    surfaces: list[Surface],
    settings: BuildSettings,
    lost: tuple[RefineZone, ...],
    report: BuildReport,
) -> tuple[tuple | None, float]:
    """The sizing field (None: uniform edges) and fTetWild's edge length where it does not
    reach, with the settings' refine zones and those at lost features (``lost``)."""
    near, far = report.settings["edge_near_mm"], report.settings["edge_far_mm"]
    zones = (*settings.refine, *lost)
    report.settings["lost_feature_zones"] = len(lost)
    if not zones and not (settings.adaptive and far > near):
        report.settings["adaptive"] = False
        return None, near
    if not settings.adaptive:  # Uniform, finer in the zones only.
        far = near
    air_far = far * AIR_FAR_RATIO if settings.adaptive else near
    air_grading = settings.air_grading if settings.adaptive else settings.grading
    sizing = _sizing_field(
        enclosure, surfaces, near, far, settings.grading, zones, air_grading, air_far
    )
    side = float(np.ptp(enclosure.vertices, axis=0).max())
    return sizing, min(max(far, air_far), OUTER_EDGE_SHARE * side)


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

    def poll(elapsed_s: float, fraction: float, stage: str) -> None:
        steps(fraction, f"tetrahedralizing (fTetWild, {stage}, {elapsed_s:.0f} s)")

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


@dataclass
class _Miss:
    """A region whose meshed surface lies beyond accuracy_mm from its input at one meshing."""

    region: str
    deviation_mm: float  # The symmetric Hausdorff distance, as in report.deviation_mm.
    strayed_mm: float  # How far the meshed surface lies from the input (the envelope's part).
    lost_mm: float  # How far the input lies from the meshed surface (a feature lost).
    features: list[dict]  # The lost features, deepest first (_lost_features).
    points: list[np.ndarray]  # Per feature: (k, 3) input points beyond the accuracy.


@dataclass
class _Meshing:
    """One meshing's result, kept until the best one is chosen."""

    vertices: np.ndarray
    tets: np.ndarray
    tet_materials: np.ndarray
    report: dict  # The report entries a meshing sets (_meshing_report).
    misses: list[_Miss]


def _meshing_report(report: BuildReport) -> dict:
    return {
        "boundary": report.boundary,
        "labels": report.labels,
        "tets_per_region": report.tets_per_region,
        "deviation_mm": report.deviation_mm,
        "envelope_mm": report.settings["envelope_mm"],
    }


def _measure_deviation(
    vertices: np.ndarray,
    tets: np.ndarray,
    inside: np.ndarray,
    regions: list[Region],
    repaired: list[Surface],
    lengths: Lengths,
    settings: BuildSettings,
    steps: _Progress,
    report: BuildReport,
) -> list[_Miss]:
    """Each region's meshed surface's deviation from its input (when measured), into the
    report and its meshing_attempts; the regions beyond accuracy_mm, with what was lost."""
    steps.begin("report", "measuring surface deviation")
    if not settings.measure_deviation:
        return []
    report.deviation_mm = {}
    misses = []
    # Every region has tets here (the meshing is made again, or fails, when one has none),
    # so each has a boundary.
    for r, region in enumerate(regions):
        faces = interface_faces(tets, inside[r])
        used, compact = np.unique(faces, return_inverse=True)
        meshed = Surface(vertices[used], compact.reshape(-1, 3))
        boundary = _boundary_part(region.name, repaired[r], lengths, report)
        strayed = one_sided_deviation(meshed, repaired[r])
        lost = one_sided_deviation(boundary, meshed)
        deviation = round(max(strayed, lost), 6)
        report.deviation_mm[region.name] = deviation
        if deviation > lengths.accuracy_mm:
            features, points = _lost_features(boundary, repaired[r], meshed, lengths.accuracy_mm)
            misses.append(_Miss(region.name, deviation, strayed, lost, features, points))
        steps(0.5 * (r + 1) / len(regions), "measuring surface deviation")
    report.meshing_attempts.append(
        {
            "envelope_mm": round(lengths.envelope_mm, 6),
            "deviation_mm": dict(report.deviation_mm),
            "lost_feature_zones": report.settings.get("lost_feature_zones", 0),
        }
    )
    return misses


def _boundary_part(name: str, surface: Surface, lengths: Lengths, report: BuildReport) -> Surface:
    """The input surface without the faces it buries inside its own volume where it crosses
    itself (they are no boundary of the solid, so no mesh follows them); counted in the
    report."""
    if not report.self_intersecting_faces.get(name):
        return surface
    buried = buried_faces(surface.vertices, surface.faces, 1e-3 * lengths.size_mm)
    if buried.any():
        report.buried_faces[name] = int(buried.sum())
        return Surface(surface.vertices, surface.faces[~buried])
    return surface


def _lost_features(
    boundary: Surface, whole: Surface, meshed: Surface, accuracy_mm: float
) -> tuple[list[dict], list[np.ndarray]]:
    """Where the input lies beyond accuracy_mm from the meshed surface: its faces there
    grouped into features (faces sharing a vertex), each with its centre, length, depth
    and thickness (along the inward normal to the input's other side, median over the
    feature). Deepest first, at most LOST_FEATURES_LISTED; and each feature's points."""
    centres = boundary.vertices[boundary.faces].mean(axis=1)
    cap = 4 * accuracy_mm
    vertex_gap = distance_to_surfaces(boundary.vertices, [meshed], cap)
    centre_gap = distance_to_surfaces(centres, [meshed], cap)
    face_gap = np.maximum(centre_gap, vertex_gap[boundary.faces].max(axis=1))
    # The Hausdorff distance samples the faces densely, these points (corners and centres)
    # do not: when none of them is beyond the accuracy, the deepest ones still show where.
    lost = np.flatnonzero(face_gap > min(accuracy_mm, LOST_FACE_SHARE * face_gap.max()))
    if len(lost) == 0 or face_gap.max() == 0:
        return [], []
    # Lost faces sharing a vertex are one feature.
    corners = boundary.faces[lost].ravel()
    owner = np.repeat(np.arange(len(lost)), 3)
    order = np.argsort(corners, kind="stable")
    same = corners[order][1:] == corners[order][:-1]
    pairs = np.column_stack([owner[order][:-1][same], owner[order][1:][same]])
    feature = components(len(lost), pairs)
    normals = face_normals(boundary.vertices, boundary.faces[lost])
    features, points = [], []
    for f in range(int(feature.max()) + 1):
        members = lost[feature == f]
        member_rows = np.flatnonzero(feature == f)
        corner_points = boundary.vertices[boundary.faces[members].ravel()]
        sample = member_rows[:: max(1, len(member_rows) // ZONES_PER_LOST_FEATURE)]
        origins = centres[lost[sample]]
        # The input's own thickness (inwards to its other side) and the gap to the next
        # surface outwards: whichever is thinner than the tets made the mesh lose this.
        areas = triangle_areas(boundary.vertices, boundary.faces[lost[sample]])
        thickness = _median_finite(
            ray_hit_distances(origins, -normals[sample], whole.vertices, whole.faces), areas
        )
        gap = _median_finite(
            ray_hit_distances(origins, normals[sample], whole.vertices, whole.faces), areas
        )
        kind, width = ("thin part", thickness)
        if gap is not None and (thickness is None or gap < thickness):
            kind, width = ("narrow gap", gap)
        features.append(
            {
                "kind": kind,
                "centre_mm": corner_points.mean(axis=0).round(3).tolist(),
                "length_mm": round(float(np.ptp(corner_points, axis=0).max()), 3),
                "thickness_mm": width,
                "deviation_mm": round(float(face_gap[members].max()), 3),
                "faces": int(len(members)),
            }
        )
        points.append(centres[lost[sample]])
    order = np.argsort([-f["deviation_mm"] for f in features], kind="stable")
    order = order[:LOST_FEATURES_LISTED]
    return [features[i] for i in order], [points[i] for i in order]


def _median_finite(values: np.ndarray, weights: np.ndarray) -> float | None:
    """The weighted median of the finite values (None when there are none): by area, the
    width of most of a feature's surface."""
    finite = np.isfinite(values)
    if not finite.any():
        return None
    order = np.argsort(values[finite])
    cumulative = np.cumsum(weights[finite][order])
    middle = order[np.searchsorted(cumulative, 0.5 * cumulative[-1])]
    return round(float(values[finite][middle]), 3)


def _refine_zones(
    misses: list[_Miss], near_mm: float, envelope_mm: float
) -> tuple[RefineZone, ...]:
    """Refine zones at the points of every lost feature that finer tets can keep: edges of
    LOST_FEATURE_EDGE_SHARE of its width. Each feature is marked ``meshed_finer``."""
    zones = []
    floor = near_mm * LOST_FEATURE_MIN_EDGE_SHARE
    for miss in misses:
        for feature, points in zip(miss.features, miss.points, strict=True):
            width = feature["thickness_mm"]
            edge = None if width is None else width * LOST_FEATURE_EDGE_SHARE
            feature["meshed_finer"] = bool(
                edge is not None and edge >= floor and width >= 2 * envelope_mm
            )
            if feature["meshed_finer"]:
                zones.extend(RefineZone(tuple(p), tuple(p), width, edge) for p in points.tolist())
    return tuple(zones)


def _emptied_error(name: str, attempts: int, lengths: Lengths) -> BuildError:
    """No meshing left the region any tet."""
    return BuildError(
        name,
        f"no tet lies inside this region after {attempts} meshings down to a "
        f"{lengths.envelope_mm:.3g} mm envelope: it is thinner than twice the envelope "
        "(40% of accuracy_mm); lower accuracy_mm",
    )


def _keep_best(
    meshings: list[_Meshing], lengths: Lengths, settings: BuildSettings, report: BuildReport
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The meshing whose worst region lies least beyond the accuracy, its entries back in
    the report. When even that one misses: BuildError with strict_accuracy, else the misses
    go into report.accuracy_not_held."""
    best = min(
        meshings,
        key=lambda m: max((miss.deviation_mm for miss in m.misses), default=0.0),
    )
    for key, value in best.report.items():
        if key == "envelope_mm":
            report.settings["envelope_mm"] = value
        else:
            setattr(report, key, value)
    if best.misses and settings.strict_accuracy:
        worst = max(best.misses, key=lambda miss: miss.deviation_mm)
        attempts = len(meshings)
        meshings_text = f"{attempts} meshing" + ("s" if attempts > 1 else "")
        deviation, accuracy = figures_apart(worst.deviation_mm, lengths.accuracy_mm)
        raise BuildError(
            worst.region,
            f"its meshed surface lies up to {deviation} mm from the input surface, "
            f"beyond accuracy_mm ({accuracy} mm), after {meshings_text} down to "
            f"a {lengths.envelope_mm:.3g} mm envelope{_lost_text(worst)}; raise accuracy_mm "
            "or report this input",
        )
    report.accuracy_not_held = [
        {
            "region": miss.region,
            "deviation_mm": miss.deviation_mm,
            "accuracy_mm": round(lengths.accuracy_mm, 6),
            "strayed_mm": round(miss.strayed_mm, 6),
            "lost_mm": round(miss.lost_mm, 6),
            "lost_features": miss.features,
        }
        for miss in best.misses
    ]
    return best.vertices, best.tets, best.tet_materials


def _lost_text(miss: _Miss) -> str:
    """'; a narrow gap 0.01 mm wide, 10 mm long, near (x, y, z) mm was lost' for the deepest
    lost feature ('' when the surface strayed rather than lost)."""
    if not miss.features or miss.lost_mm < miss.strayed_mm:
        return ""
    feature = miss.features[0]
    width = feature["thickness_mm"]
    size = ""
    if width is not None:
        size = f" {width:.2g} mm " + ("wide" if feature["kind"] == "narrow gap" else "thick")
    centre = ", ".join(f"{c:.1f}" for c in feature["centre_mm"])
    return (
        f"; a {feature['kind']}{size}, {feature['length_mm']:.2g} mm long, near ({centre}) mm "
        "was lost"
    )
