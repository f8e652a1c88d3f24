"""The scene's checks, shown in the panel: Blender's own (exchange.scene_problems, the
modifier stacks, closed parts of one region that touch) here; the toolkit's on the meshes
(``build-request --check``) run as a child like the build (building.start_check). Every
problem recorded says where it lies on the object (mesh_places) and what to do
(problem_remedies)."""

from __future__ import annotations

import re

import bpy

from . import exchange, mesh_places, problem_remedies

TOUCHING = "closed parts touch"


def record(scene, problems: list[exchange.SceneProblemError]) -> list[str]:
    """Put the problems, placed and with their remedies, into the scene's list (the panel
    draws it); their messages."""
    settings = scene.hapticut
    settings.problems.clear()
    for problem in problems:
        if not problem.place:
            problem.place = _locate(scene, problem)
        problem.remedy = problem.remedy or problem_remedies.remedy(problem.problem)
        item = settings.problems.add()
        item.object_name, item.problem = problem.object_name, problem.problem
        item.place, item.remedy = problem.place, problem.remedy
    return [problem.message() for problem in problems]


def check_scene(context) -> list[str]:
    """Blender's checks; the problems are recorded in the scene and returned as messages."""
    scene = context.scene
    problems = exchange.scene_problems(scene)
    if not problems:
        problems = _touching_parts(scene, context.evaluated_depsgraph_get())
    return record(scene, problems)


def _touching_parts(scene, depsgraph) -> list[exchange.SceneProblemError]:
    problems = []
    for obj in exchange.scene_objects(scene, "REGION"):
        mesh = _mesh(obj, depsgraph)
        if mesh is None:
            continue
        touching, points = mesh_places.touching_parts(mesh)
        if len(touching):
            place = mesh_places.place_text(mesh, scene, touching, points)
            problems.append(exchange.SceneProblemError(obj.name, TOUCHING, place))
    return problems


def _mesh(obj, depsgraph) -> mesh_places.Mesh | None:
    """The object's evaluated mesh, or None when it is too large to search in the UI's time
    (or cannot be evaluated: the toolkit's check names that)."""
    try:
        mesh = mesh_places.Mesh(obj, depsgraph)
    except (RuntimeError, AttributeError):
        return None
    return mesh if 0 < len(mesh.triangles) <= mesh_places.MAX_TRIANGLES else None


def _locate(scene, problem: exchange.SceneProblemError) -> str:
    """Where the toolkit's problem lies on its object ("" when not found or not a place)."""
    obj = bpy.data.objects.get(problem.object_name) if problem.object_name else None
    if obj is None or obj.type != "MESH":
        return ""
    depsgraph = bpy.context.evaluated_depsgraph_get()
    mesh = _mesh(obj, depsgraph)
    if mesh is None:
        return ""
    text = problem.problem
    other = re.search(r"region '([^']+)'", text)
    other_mesh = None
    if other is not None and bpy.data.objects.get(other.group(1)) is not None:
        other_mesh = _mesh(bpy.data.objects[other.group(1)], depsgraph)
    points = None
    if "intersects itself" in text:
        triangles = mesh_places.self_crossing(mesh)
    elif "the mesh is open" in text:
        triangles, points = mesh_places.edge_faces(mesh, lambda uses: uses == 1)
    elif "not manifold" in text:
        triangles, points = mesh_places.edge_faces(mesh, lambda uses: uses > 2)
    elif "crosses region" in text and other_mesh is not None:
        triangles = mesh_places.crossing_other(mesh, other_mesh)
    elif "comes within" in text and other_mesh is not None:
        triangles = mesh_places.nearest_to_other(mesh, other_mesh)
    else:
        return ""
    return mesh_places.place_text(mesh, scene, triangles, points)
