"""Scene -> tree -> bytes: the writer's half of format version 1.

Every section is written, defaults included, so a file says everything. The JSON layout is
the one core/src/scene_io.cpp writes: indented by two spaces, except that an array holding no
arrays or objects stays on one line (one vertex or tet per line).
"""

from __future__ import annotations

import json
from dataclasses import asdict
from itertools import chain
from typing import Any

import msgpack
import numpy as np

from .model import FORMAT_NAME, FORMAT_VERSION, MODEL_PARAMETERS, UNITS, Scene

_NUMBER_TYPES = {int, float}


def scene_to_tree(scene: Scene) -> dict[str, Any]:
    return {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "units": dict(UNITS),
        "coupling": {
            "stiffness_N_per_mm": scene.stiffness_N_per_mm,
            "servo_rate_Hz": scene.servo_rate_Hz,
        },
        "tolerance_mm": scene.tolerance_mm,
        "safety": asdict(scene.safety),
        "materials": [_material_tree(material) for material in scene.materials],
        "mesh": {
            "vertices": _float_rows(scene.vertices),
            "tets": np.asarray(scene.tets).tolist(),
            "tet_materials": np.asarray(scene.tet_materials).tolist(),
        },
        "blades": [
            {
                "name": blade.name,
                "start_mm": list(blade.start_mm),
                "end_mm": list(blade.end_mm),
                "points": blade.points,
            }
            for blade in scene.blades
        ],
        "metadata": scene.metadata,
    }


def _material_tree(material) -> dict[str, Any]:
    tree = {"name": material.name, "model": material.model}
    for key in MODEL_PARAMETERS.get(material.model, {}):
        tree[key] = getattr(material, key)
    return tree


def _float_rows(vertices: Any) -> list:
    array = np.asarray(vertices)
    if array.dtype.kind in "iuf":  # Numbers are written as doubles, as C++ does.
        array = array.astype(np.float64)
    return array.tolist()


def encode_json(tree: dict[str, Any]) -> bytes:
    parts: list[str] = []
    _append_layout(parts, tree, 0)
    parts.append("\n")
    return "".join(parts).encode("utf-8")


def encode_msgpack(tree: dict[str, Any]) -> bytes:
    return msgpack.packb(tree, use_bin_type=True)


def _dumps(value: Any) -> str:
    return json.dumps(value, ensure_ascii=False, allow_nan=False, separators=(",", ":"))


def _is_container(value: Any) -> bool:
    return isinstance(value, dict | list | tuple)


def _append_layout(parts: list[str], value: Any, depth: int) -> None:
    indent = "  " * (depth + 1)
    if isinstance(value, dict) and value:
        parts.append("{\n")
        for i, (key, item) in enumerate(value.items()):
            parts.append(f",\n{indent}" if i else indent)
            parts.append(f"{_dumps(str(key))}: ")
            _append_layout(parts, item, depth + 1)
        parts.append(f"\n{'  ' * depth}}}")
    elif isinstance(value, list | tuple) and any(map(_is_container, value)):
        if _is_number_table(value):  # The mesh: one C-speed dumps instead of one per row.
            rows = _dumps(value)[1:-1].replace("],[", f"],\n{indent}[")
            parts.append(f"[\n{indent}{rows}\n{'  ' * depth}]")
            return
        parts.append("[\n")
        for i, item in enumerate(value):
            parts.append(f",\n{indent}" if i else indent)
            _append_layout(parts, item, depth + 1)
        parts.append(f"\n{'  ' * depth}]")
    else:
        parts.append(_dumps(value))


def _is_number_table(rows: list | tuple) -> bool:
    """Rows that are all lists of plain numbers (so "],[" only ever separates rows)."""
    return (
        set(map(type, rows)) <= {list, tuple}
        and set(map(type, chain.from_iterable(rows))) <= _NUMBER_TYPES
    )
