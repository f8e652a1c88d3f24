"""The scene's checks, shown in the panel: Blender's own (exchange.scene_problems, the
modifier stacks) here; the toolkit's on the meshes (``build-request --check``) run as a
child like the build (building.start_check)."""

from __future__ import annotations

from . import exchange


def record(scene, problems: list[exchange.SceneProblemError]) -> list[str]:
    """Put the problems into the scene's list (the panel draws it); their messages."""
    settings = scene.hapticut
    settings.problems.clear()
    for problem in problems:
        item = settings.problems.add()
        item.object_name, item.problem = problem.object_name, problem.problem
    return [str(p) for p in problems]


def check_scene(context) -> list[str]:
    """Blender's checks; the problems are recorded in the scene and returned as messages."""
    scene = context.scene
    return record(scene, exchange.scene_problems(scene))
