"""What the add-on writes for the builder (docs/addon.md): a build request JSON and one .npz
per region (vertices in mm, world coordinates, modifiers applied; triangles), and the
material of each region from the toolkit's table. Also the checks that only Blender can do."""

from __future__ import annotations

import hashlib
import json
import os

import numpy as np

from ..toolkit import materials
from ..toolkit.units import mm_per_unit

REQUEST_FORMAT = "hapticut.build-request"
REQUEST_VERSION = 1
SCENE_FILE = "scene.hapticut.msgpack"


class SceneProblemError(Exception):
    """An object the scene cannot use: ``object_name`` and ``problem`` for the panel, with
    ``place`` (where on the object, mesh_places) and ``remedy`` (what to do) when known."""

    def __init__(self, object_name: str, problem: str, place: str = "", remedy: str = ""):
        self.object_name, self.problem = object_name, problem
        self.place, self.remedy = place, remedy
        super().__init__(self.message())

    def __str__(self) -> str:
        return self.message()

    def message(self) -> str:
        text = f"{self.object_name}: {self.problem}" if self.object_name else self.problem
        text += f", {self.place}" if self.place else ""
        return text + (f". To fix: {self.remedy}" if self.remedy else "")


def scene_objects(scene, role: str) -> list:
    return [o for o in scene.objects if o.hapticut.role == role]


def evaluated_triangles(obj, depsgraph, mm: float) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (n, 3) mm world, triangles (f, 3) int32) of the object with its modifiers."""
    try:
        evaluated = obj.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
    except RuntimeError as error:
        raise SceneProblemError(
            obj.name, f"its modifier stack cannot be evaluated ({error})"
        ) from None
    try:
        if mesh is None:
            raise SceneProblemError(obj.name, "its modifier stack cannot be evaluated (no mesh)")
        mesh.calc_loop_triangles()
        count = len(mesh.vertices)
        local = np.empty(count * 3, np.float64)
        mesh.vertices.foreach_get("co", local)
        triangles = np.empty(len(mesh.loop_triangles) * 3, np.int32)
        mesh.loop_triangles.foreach_get("vertices", triangles)
        matrix = np.array(evaluated.matrix_world, np.float64)
    finally:
        evaluated.to_mesh_clear()
    if len(triangles) == 0:
        has_faces = obj.type == "MESH" and len(obj.data.polygons) > 0
        why = (
            "its modifier stack cannot be evaluated: it leaves no faces"
            if has_faces
            else "it has no faces"
        )
        raise SceneProblemError(obj.name, why)
    local = local.reshape(-1, 3)
    world = local @ matrix[:3, :3].T + matrix[:3, 3]
    return world * mm, triangles.reshape(-1, 3)


def region_material(obj, table: dict) -> dict:
    """The region's material as the request writes it ({name, model, parameters...}, and
    ``cut`` when its cut tets become something else)."""
    settings = obj.hapticut
    if settings.material_preset != "custom":
        preset = materials.preset(table, settings.material_preset)
        if preset is None:
            names = ", ".join(p["name"] for p in table["presets"])
            raise SceneProblemError(
                obj.name,
                f"material preset {settings.material_preset!r} is not one of {names} (or custom)",
            )
        material = {"name": preset["name"], "model": preset["model"], **preset["parameters"]}
        return _with_cut(obj, material, materials.model(table, preset["model"]))
    model = materials.model(table, settings.custom_model)
    if model is None:
        names = ", ".join(m["name"] for m in table["models"])
        raise SceneProblemError(
            obj.name, f"material model {settings.custom_model!r} is not one of {names}"
        )
    values = {item.name: item.value for item in settings.custom_parameters}
    material = {"name": settings.custom_name or obj.name, "model": model["name"]}
    for parameter in model["parameters"]:
        name = parameter["name"]
        value = values.get(name, parameter["default"])
        if not materials.in_range(parameter, value):
            raise SceneProblemError(
                obj.name, f"{name} = {value:g} is outside {materials.range_text(parameter)}"
            )
        material[name] = float(value)
    return _with_cut(obj, material, model)


def _with_cut(obj, material: dict, model: dict | None) -> dict:
    """The material with the request's ``cut`` from the region's *Once cut*: none when it
    stays as it is, or when a blade never cuts its model (the panel says the setting has no
    effect there)."""
    settings = obj.hapticut
    if settings.cut_becomes == "UNCHANGED" or not materials.cuttable(model):
        return material
    if settings.cut_becomes == "FREE":
        return {**material, "cut": {"becomes": "free"}}
    factor = settings.cut_factor
    if not 0.0 < factor <= 1.0:
        raise SceneProblemError(
            obj.name,
            f"Once cut: Factor {factor:g} is outside (0, 1]",
            remedy="a factor of 0 leaves no resistance: choose Free",
        )
    return {**material, "cut": {"becomes": "weaker", "factor": float(factor)}}


def fill_custom_parameters(obj, table: dict) -> None:
    """The custom model's parameters at their defaults (keeping values already set)."""
    settings = obj.hapticut
    model = materials.model(table, settings.custom_model)
    if model is None:
        return
    old = {item.name: item.value for item in settings.custom_parameters}
    settings.custom_parameters.clear()
    for parameter in model["parameters"]:
        item = settings.custom_parameters.add()
        item.name = parameter["name"]
        item.value = old.get(parameter["name"], parameter["default"])


def blade_edge_mm(obj, mm: float) -> tuple[list[float], list[float]]:
    """The blade's cutting edge in its tool frame (the object's origin and axes, its scale
    applied), in mm."""
    settings = obj.hapticut
    scale = np.array(obj.matrix_world.to_scale(), np.float64)
    if settings.edge_mode == "AXIS":
        if settings.edge_length <= 0:
            raise SceneProblemError(obj.name, "the blade has no cutting edge (its length is 0)")
        axis = np.zeros(3)
        axis["XYZ".index(settings.edge_axis)] = settings.edge_length / 2
        start, end = -axis * mm, axis * mm
    else:
        count = len(obj.data.vertices) if obj.type == "MESH" else 0
        a, b = settings.edge_vertex_a, settings.edge_vertex_b
        if not (0 <= a < count and 0 <= b < count) or a == b:
            raise SceneProblemError(
                obj.name,
                "the blade has no cutting edge (pick two vertices in edit "
                "mode and Set Cutting Edge)",
            )
        start = np.array(obj.data.vertices[a].co, np.float64) * scale * mm
        end = np.array(obj.data.vertices[b].co, np.float64) * scale * mm
    if np.linalg.norm(end - start) <= 0:
        raise SceneProblemError(obj.name, "the blade has no cutting edge (its two ends coincide)")
    return start.tolist(), end.tolist()


def scene_problems(scene) -> list[SceneProblemError]:
    """What Blender alone can see is wrong before anything runs (the toolkit checks the
    meshes' geometry: open, self-intersecting, without volume)."""
    problems = []
    regions, blades = scene_objects(scene, "REGION"), scene_objects(scene, "BLADE")
    if not regions:
        problems.append(SceneProblemError("", "no region: mark a closed mesh as a Region"))
    if not blades:
        problems.append(SceneProblemError("", "no blade: mark an object as a Blade"))
    for obj in regions:
        if obj.type != "MESH":
            problems.append(SceneProblemError(obj.name, f"a region must be a mesh, not {obj.type}"))
    mm = mm_per_unit(scene)
    for obj in blades:
        try:
            blade_edge_mm(obj, mm)
        except SceneProblemError as problem:
            problems.append(problem)
    return problems


def write_request(scene, depsgraph, table: dict, folder: str) -> tuple[str, str]:
    """Write the request and its meshes into folder; (request path, digest of the build).

    Raises Problem for the first object that cannot be written."""
    mm = mm_per_unit(scene)
    settings = scene.hapticut
    digest = hashlib.sha256()
    regions = []
    os.makedirs(folder, exist_ok=True)
    for index, obj in enumerate(scene_objects(scene, "REGION")):
        vertices, faces = evaluated_triangles(obj, depsgraph, mm)
        mesh_file = f"region-{index}.npz"
        np.savez(os.path.join(folder, mesh_file), vertices=vertices, faces=faces)
        digest.update(vertices.tobytes())
        digest.update(faces.tobytes())
        regions.append(
            {"name": obj.name, "mesh": mesh_file, "material": region_material(obj, table)}
        )
    blades = []
    for obj in scene_objects(scene, "BLADE"):
        start, end = blade_edge_mm(obj, mm)
        blades.append(
            {
                "name": obj.name,
                "start_mm": start,
                "end_mm": end,
                "points": obj.hapticut.blade_points,
                "coupling": obj.hapticut.blade_coupling.lower(),
                "orientation": obj.hapticut.blade_orientation.lower(),
                "device": obj.hapticut.device,
            }
        )
    build_settings = {"enclosure": settings.enclosure, "coarsen": settings.coarsen}
    for key, value in (
        ("accuracy_mm", settings.accuracy),
        ("edge_near_mm", settings.edge_near),
        ("edge_far_mm", settings.edge_far),
    ):
        if value > 0:
            build_settings[key] = value * mm
    request = {
        "format": REQUEST_FORMAT,
        "version": REQUEST_VERSION,
        "regions": regions,
        "blades": blades,
        "settings": build_settings,
        "scene_file": SCENE_FILE,
    }
    text = json.dumps(request, indent=1, sort_keys=True)
    digest.update(text.encode())
    path = os.path.join(folder, "request.json")
    with open(path, "w", encoding="utf-8") as file:
        file.write(text)
    return path, digest.hexdigest()
