"""A build request: what the Blender add-on writes for the builder (docs/addon.md).

The request is a JSON file beside the regions' meshes (``.npz`` files holding ``vertices``
(n, 3) float64 mm, world coordinates, and ``faces`` (f, 3) integer). ``read_request`` turns it
into the builder's own inputs (Region, BladeSpec, BuildSettings); ``input_problems`` lists what
is wrong with the regions before anything is meshed, each problem naming its region.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, fields, replace

import numpy as np

from hapticut.cut_surface import CUTTABLE_MODELS
from hapticut.scenebuild import BuildError, BuildSettings, Region, cut_variant
from hapticut.scenebuild.geometry import signed_volume
from hapticut.scenefile import BLADE_COUPLINGS, BLADE_ORIENTATIONS, BladeSpec, Material
from hapticut.scenefile.model import MATERIAL_PARAMETERS

REQUEST_FORMAT = "hapticut.build-request"
REQUEST_VERSION = 1
# The BuildSettings fields a request may set (the rest keep the builder's defaults).
SETTINGS_FIELDS = (
    "enclosure",
    "margin_mm",
    "accuracy_mm",
    "edge_near_mm",
    "edge_far_mm",
    "grading",
    "adaptive",
    "simplify",
    "coarsen",
    "threads",
)
# What a material's cut tets become ("cut" of a region's material; none: they stay as they
# are): free (the air's material), or a weaker copy of the material (builder.cut_variant).
CUT_CHOICES = ("free", "weaker")
# A region whose |volume| is below this fraction of its bounding box's volume encloses none.
ZERO_VOLUME_RATIO = 1e-9


class RequestError(ValueError):
    """A request the builder cannot read: ``field`` names the entry, the message the reason."""

    def __init__(self, field: str, reason: str) -> None:
        super().__init__(f"{field}: {reason}")
        self.field = field
        self.reason = reason


@dataclass(frozen=True)
class BuildRequest:
    """A request read and checked: the builder's inputs and the blades' device names."""

    regions: list[Region]
    blades: list[BladeSpec]
    settings: BuildSettings
    blade_devices: dict[str, str]
    scene_file: str  # The scene's file name inside the output directory.


def _expect(condition: bool, field: str, reason: str) -> None:
    if not condition:
        raise RequestError(field, reason)


def _number(value, field: str) -> float:
    _expect(
        isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value),
        field,
        f"must be a finite number, not {value!r}",
    )
    return float(value)


def _material(data, field: str) -> Material:
    _expect(isinstance(data, dict), field, "must be an object")
    _expect(isinstance(data.get("name"), str) and data["name"], f"{field}/name", "missing")
    _expect(isinstance(data.get("model"), str), f"{field}/model", "missing")
    values = {}
    for key, value in data.items():
        if key in ("name", "model", "cut"):
            continue
        _expect(key in MATERIAL_PARAMETERS, f"{field}/{key}", "not a material parameter")
        values[key] = _number(value, f"{field}/{key}")
    try:
        return Material(name=data["name"], model=data["model"], **values)
    except TypeError as error:
        raise RequestError(field, str(error)) from None


def _cut(data, material: Material, field: str, air: Material) -> tuple[Material, Material | None]:
    """The material with the cut_to its ``cut`` entry asks for, and the weaker copy it names
    (None when the scene has the material already: the air)."""
    _expect(isinstance(data, dict), field, "must be an object")
    _expect(
        material.model in CUTTABLE_MODELS,
        field,
        f"material {material.name!r} is {material.model}: a blade never cuts it, so it takes "
        f"no cut variant (only {', '.join(CUTTABLE_MODELS)} do)",
    )
    becomes = data.get("becomes")
    _expect(
        becomes in CUT_CHOICES,
        f"{field}/becomes",
        f"must be one of {', '.join(CUT_CHOICES)}, not {becomes!r}",
    )
    allowed = {"becomes", "factor"} if becomes == "weaker" else {"becomes"}
    unknown = sorted(set(data) - allowed)
    _expect(
        not unknown,
        f"{field}/{unknown[0] if unknown else ''}",
        f"not a setting of a {becomes} cut variant",
    )
    if becomes == "free":
        return replace(material, cut_to=air.name), None
    _expect("factor" in data, f"{field}/factor", "required field missing")
    factor = _number(data["factor"], f"{field}/factor")
    _expect(
        0.0 < factor <= 1.0,
        f"{field}/factor",
        f'must be in (0, 1], not {factor:g} (0 leaves no resistance: "becomes": "free")',
    )
    variant = cut_variant(material, factor)
    return replace(material, cut_to=variant.name), variant


def _region(data, field: str, folder: str, air: Material) -> Region:
    _expect(isinstance(data, dict), field, "must be an object")
    name = data.get("name")
    _expect(isinstance(name, str) and name, f"{field}/name", "missing")
    mesh = data.get("mesh")
    _expect(isinstance(mesh, str) and mesh, f"{field}/mesh", "missing")
    path = os.path.join(folder, mesh)
    try:
        with np.load(path, allow_pickle=False) as arrays:
            vertices, faces = arrays["vertices"], arrays["faces"]
    except (OSError, KeyError, ValueError) as error:
        raise RequestError(f"{field}/mesh", f"cannot read {path}: {error}") from None
    material_data = data.get("material")
    material = _material(material_data, f"{field}/material")
    cut_material = None
    if "cut" in material_data:
        material, cut_material = _cut(material_data["cut"], material, f"{field}/material/cut", air)
    return Region(name, vertices, faces, material, cut_material)


def _blade(data, field: str) -> tuple[BladeSpec, str]:
    _expect(isinstance(data, dict), field, "must be an object")
    name = data.get("name")
    _expect(isinstance(name, str) and name, f"{field}/name", "missing")
    ends = []
    for key in ("start_mm", "end_mm"):
        point = data.get(key)
        _expect(isinstance(point, list) and len(point) == 3, f"{field}/{key}", "must be [x, y, z]")
        ends.append(tuple(_number(v, f"{field}/{key}") for v in point))
    points = data.get("points", 50)
    _expect(
        isinstance(points, int) and not isinstance(points, bool) and points >= 2,
        f"{field}/points",
        f"must be an integer of at least 2, not {points!r}",
    )
    device = data.get("device", "")
    _expect(isinstance(device, str), f"{field}/device", "must be a string")
    settings = {}
    for key, choices in (("coupling", BLADE_COUPLINGS), ("orientation", BLADE_ORIENTATIONS)):
        value = data.get(key, choices[0])
        _expect(
            value in choices,
            f"{field}/{key}",
            f"must be one of {', '.join(choices)}, not {value!r} (blade {name!r})",
        )
        settings[key] = value
    return BladeSpec(name, ends[0], ends[1], points, **settings), device


def _settings(settings_data) -> BuildSettings:
    _expect(isinstance(settings_data, dict), "settings", "must be an object")
    unknown = sorted(set(settings_data) - set(SETTINGS_FIELDS))
    _expect(not unknown, f"settings/{unknown[0] if unknown else ''}", "not a build setting")
    known = {f.name for f in fields(BuildSettings)}
    assert set(SETTINGS_FIELDS) <= known
    try:
        return BuildSettings(**settings_data)
    except TypeError as error:
        raise RequestError("settings", str(error)) from None


def read_request(path: str | os.PathLike) -> BuildRequest:
    """The request at path, its meshes read from beside it; RequestError names a bad entry."""
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as file:
            data = json.load(file)
    except (OSError, json.JSONDecodeError) as error:
        raise RequestError("(root)", f"cannot read {path}: {error}") from None
    _expect(isinstance(data, dict), "(root)", "must be a JSON object")
    _expect(data.get("format") == REQUEST_FORMAT, "format", f"must be {REQUEST_FORMAT!r}")
    _expect(data.get("version") == REQUEST_VERSION, "version", f"must be {REQUEST_VERSION}")
    folder = os.path.dirname(os.path.abspath(path))
    settings = _settings(data.get("settings", {}))
    regions = data.get("regions")
    _expect(isinstance(regions, list), "regions", "must be a list")
    regions = [
        _region(item, f"regions/{i}", folder, settings.air) for i, item in enumerate(regions)
    ]
    blades_data = data.get("blades", [])
    _expect(isinstance(blades_data, list), "blades", "must be a list")
    blades_and_devices = [_blade(item, f"blades/{i}") for i, item in enumerate(blades_data)]
    scene_file = data.get("scene_file", "scene.hapticut.msgpack")
    _expect(
        isinstance(scene_file, str)
        and os.path.basename(scene_file) == scene_file
        and scene_file.endswith((".hapticut.json", ".hapticut.msgpack")),
        "scene_file",
        "must be a file name ending in .hapticut.json or .hapticut.msgpack",
    )
    return BuildRequest(
        regions=regions,
        blades=[blade for blade, _ in blades_and_devices],
        settings=settings,
        blade_devices={blade.name: device for blade, device in blades_and_devices if device},
        scene_file=scene_file,
    )


def input_problems(regions: list[Region], progress=None) -> list[tuple[str, str]]:
    """(region, problem) for each region that is open, self-intersecting or without volume,
    before any repair: the add-on asks its user to fix these rather than have them patched.
    progress(fraction, message), when given, is told which region is checked."""
    return InputCheck(regions, progress, beside=False).problems()


# Regions of at least this many faces in all have their crossing faces looked for beside
# the caller's work (InputCheck): on fewer, that costs less than starting a process.
BESIDE_FACES = 20_000


class InputCheck:
    """input_problems' checks, begun. With ``beside``, the dearest, faces crossing others,
    runs in a forked child (hapticut.scenebuild.forked, where the process allows it) on
    regions of at least BESIDE_FACES faces, while the caller goes on (Check Scene checks the
    layout meanwhile). problems() waits for it; failed() says, without waiting, whether a
    problem is known. Close it (or use it as a context manager) to end the child."""

    def __init__(self, regions: list[Region], progress=None, beside: bool = True) -> None:
        from hapticut.scenebuild.forked import Beside
        from hapticut.scenebuild.geometry import Surface
        from hapticut.scenebuild.repair import _meshlab, check_arrays

        # The problems in the order reported: (region, problem), or (region, None) where its
        # crossing faces are told.
        self.found: list[tuple[str, str | None]] = []
        surfaces: list[Surface] = []
        for i, region in enumerate(regions):
            if progress is not None:
                progress(i / len(regions), f"checking {region.name} ({len(region.faces):,} faces)")
            try:
                vertices, faces = check_arrays(region.name, region.vertices, region.faces)
            except BuildError as error:
                self.found.append((region.name, error.problem))
                continue
            edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1).astype(np.int64)
            # Each edge as one number (unique over rows sorts much slower on a scan).
            _, uses = np.unique(edges[:, 0] * len(vertices) + edges[:, 1], return_counts=True)
            open_edges = int((uses == 1).sum())
            if open_edges:
                self.found.append((region.name, f"the mesh is open ({open_edges} boundary edges)"))
            if (uses > 2).any():
                self.found.append(
                    (region.name, f"the mesh is not manifold ({int((uses > 2).sum())} edges)")
                )
            self.found.append((region.name, None))
            surfaces.append(Surface(vertices, faces))
            extent = vertices.max(axis=0) - vertices.min(axis=0)
            volume = abs(signed_volume(vertices, faces))
            if volume <= ZERO_VOLUME_RATIO * max(float(np.prod(extent)), float(extent.max()) ** 3):
                self.found.append((region.name, f"the region has no volume ({volume:.3g} mm^3)"))
        names = [region.name for region in regions]
        for name in sorted({n for n in names if names.count(n) > 1}):
            self.found.append((name, "two regions have this name"))
        self.known = any(problem is not None for _, problem in self.found)
        self.work = _crossing_counts(surfaces)
        beside = beside and sum(len(s.faces) for s in surfaces) >= BESIDE_FACES
        if beside:
            _meshlab()  # Imported once, here, rather than again by the child and the caller.
        self.beside = Beside(self.work) if beside else None
        if self.beside is not None and not self.beside.forked:
            self.beside = None  # Not forked after all: the work is done here when asked.
        self.counts: list[int] | None = None

    def failed(self) -> bool:
        """Whether a problem is known now: the child's answer is not waited for, but without
        a child the crossing faces are looked for at once."""
        answered = self.beside is None or self.beside.ready()
        if not self.known and self.counts is None and answered:
            self.known = any(self._counts())
        return self.known

    def _counts(self) -> list[int]:
        """Each surface's count of crossing faces (waits for the child)."""
        if self.counts is None:
            self.counts = self.beside.result() if self.beside is not None else self.work()
        return self.counts

    def problems(self) -> list[tuple[str, str]]:
        counts = iter(self._counts())
        problems = []
        for region, problem in self.found:
            if problem is None:
                crossing = next(counts)
                if not crossing:
                    continue
                problem = f"the mesh intersects itself ({crossing} faces)"
            problems.append((region, problem))
        return problems

    def close(self) -> None:
        """End the child, if one still runs."""
        if self.beside is not None:
            self.beside.close()

    def __enter__(self) -> InputCheck:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _crossing_counts(surfaces):
    """work() counting each surface's faces that cross another of its faces."""
    from hapticut.scenebuild.repair import self_intersecting_faces

    def work() -> list[int]:
        return [int(self_intersecting_faces([surface]).sum()) for surface in surfaces]

    return work
