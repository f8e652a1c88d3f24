"""The scene's checks, shown in the panel: Blender's own (exchange.scene_problems, the
modifier stacks) and, on request, the toolkit's on the meshes (``build-request --check``)."""

from __future__ import annotations

import json
import shutil
import subprocess
import tempfile

from . import exchange, preferences, toolkit


def record(scene, problems: list[exchange.SceneProblemError]) -> list[str]:
    """Put the problems into the scene's list (the panel draws it); their messages."""
    settings = scene.hapticut
    settings.problems.clear()
    for problem in problems:
        item = settings.problems.add()
        item.object_name, item.problem = problem.object_name, problem.problem
    return [str(p) for p in problems]


def toolkit_problems(executable: str, request: str) -> list[exchange.SceneProblemError]:
    try:
        done = subprocess.run(
            [executable, "build-request", request, "--check"],
            capture_output=True,
            text=True,
            timeout=toolkit.QUICK_TIMEOUT_S,
            env=toolkit.child_environment(),
        )
    except (OSError, subprocess.TimeoutExpired) as error:
        return [exchange.SceneProblemError("", f"hapticut build-request --check: {error}")]
    problems = []
    for line in done.stdout.splitlines():
        try:
            event = json.loads(line)
        except json.JSONDecodeError:
            continue
        if event.get("event") in ("problem", "error"):
            problems.append(
                exchange.SceneProblemError(event.get("object", ""), event.get("problem", ""))
            )
    if done.returncode != 0 and not problems:
        problems.append(exchange.SceneProblemError("", toolkit.last_error_line(done.stderr)))
    return problems


def check_scene(context, with_toolkit: bool) -> list[str]:
    """Every check; the problems are recorded in the scene and returned as messages."""
    scene = context.scene
    problems = exchange.scene_problems(scene)
    if problems or not with_toolkit:
        return record(scene, problems)
    folder = tempfile.mkdtemp(prefix="hapticut-check-")
    try:
        table = preferences.material_table(context)
        request, _ = exchange.write_request(scene, context.evaluated_depsgraph_get(), table, folder)
        problems = toolkit_problems(preferences.executable(context), request)
    except exchange.SceneProblemError as problem:
        problems = [problem]
    except toolkit.ToolkitError as error:
        problems = [exchange.SceneProblemError("", str(error))]
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return record(scene, problems)
