"""Shared by the scene-format tests: the example scene, the bad-input table, a big mesh."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import numpy as np
from hapticut.scenebuild.geometry import kuhn_grid
from hapticut.scenefile import Material, Scene

DATA_DIR = Path(__file__).resolve().parents[1] / "data"
EXAMPLE_PATH = DATA_DIR / "two_tets.hapticut.json"
ERROR_CASES = json.loads((DATA_DIR / "scene_error_cases.json").read_text())["cases"]


def example_tree() -> dict[str, Any]:
    return json.loads(EXAMPLE_PATH.read_text())


def _unescape(token: str) -> str:
    return token.replace("~1", "/").replace("~0", "~")


def apply_patch(document: Any, patch: list[dict[str, Any]]) -> Any:
    """RFC 6902 add / replace / remove, enough for scene_error_cases.json."""
    document = copy.deepcopy(document)
    for operation in patch:
        op, path, value = operation["op"], operation["path"], operation.get("value")
        if path == "":
            document = copy.deepcopy(value)
            continue
        *parents, last = (_unescape(token) for token in path.split("/")[1:])
        target = document
        for key in parents:
            target = target[int(key)] if isinstance(target, list) else target[key]
        if isinstance(target, list):
            index = len(target) if last == "-" else int(last)
            if op == "add":
                target.insert(index, copy.deepcopy(value))
            elif op == "replace":
                target[index] = copy.deepcopy(value)
            else:
                del target[index]
        elif op == "remove":
            del target[last]
        else:
            target[last] = copy.deepcopy(value)
    return document


def grid_scene(cells_per_side: int) -> Scene:
    """A box of unit cubes, 6 positively oriented Kuhn tets each (6 n^3 tets), two materials
    in alternating layers of cells."""
    n = cells_per_side
    vertices, tets = kuhn_grid(np.zeros(3), np.full(3, float(n)), (n, n, n))
    layer = np.floor(vertices[tets].mean(axis=1)[:, 2]).astype(np.int64) % 2
    return Scene(
        materials=[Material("air", "free"), Material("flesh", "drag", drag_distance_mm=1.0)],
        vertices=vertices,
        tets=tets.astype(np.int32),
        tet_materials=layer.astype(np.int32),
    )
