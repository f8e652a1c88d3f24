"""Both scene readers give the same first error on mutated files (issue 8, defect 9).

Seeded mutations of two valid scenes, in both encodings: byte edits (flip, insert, delete,
truncate, repeat a run) and tree edits (replace a value with one of many bad values, drop a key,
add a key, nest deeper). For every file the C++ reader (hapticut._core) and the Python reader
(hapticut.scene) must both accept it with the same scene, or both reject it with the same message.
HAPTICUT_MUTATIONS sets the number of files per seed and encoding (default 750: 3000 in all).
"""

from __future__ import annotations

import json
import math
import os
import random
from pathlib import Path

import msgpack
import numpy as np
import pytest
from hapticut import _core
from hapticut.scene import JSON, MSGPACK, SceneError, parse_scene, scene_from_dict

DATA = Path(__file__).resolve().parents[1] / "data"
COUNT = int(os.environ.get("HAPTICUT_MUTATIONS", "750"))

BAD_VALUES = [
    None, True, False, 0, -1, 1, 2, 3, 2.5, -0.5, 1e-300, 1e6, 1e9, 1e20, 1e308, 2**31, 2**63,
    2**64 - 1, -(2**63), math.nan, math.inf, -math.inf, "", "x", "free", "rigid", "drag", "1",
    [], [0], [0, 1], [0, 1, 2], [0, 1, 2, 3], [[0, 0, 0]], {}, {"a": 1}, b"\x00\xff",
]  # fmt: skip


def seeds() -> list[dict]:
    example = json.loads((DATA / "two_tets.hapticut.json").read_text())
    viscous = json.loads(json.dumps(example))
    viscous["materials"].append({"name": "fat", "model": "viscous", "viscosity_N_s_per_mm": 0.002})
    viscous["materials"].append({"name": "skin", "model": "membrane", "break_force_N": 1.5})
    viscous["mesh"]["tet_materials"] = [2, 3]
    viscous["safety"] = {"max_force_N": 5.0, "max_transitions_per_tick": 64, "ramp_time_s": 0.5}
    return [example, viscous]


def paths(tree, prefix=()):
    """Every (container, key) in the tree, in document order."""
    out = []
    items = tree.items() if isinstance(tree, dict) else enumerate(tree)
    for key, value in items:
        out.append((tree, key))
        if isinstance(value, dict | list):
            out.extend(paths(value, (*prefix, key)))
    return out


def mutate_tree(tree, rng: random.Random):
    tree = json.loads(json.dumps(tree))
    for _ in range(rng.choice((1, 1, 1, 2, 3))):
        container, key = rng.choice(paths(tree))
        op = rng.random()
        if op < 0.6:
            container[key] = rng.choice(BAD_VALUES)
        elif op < 0.75 and isinstance(container, dict):
            del container[key]
        elif op < 0.85 and isinstance(container, dict):
            container[rng.choice(["extra", "model", "name", "tolerance_mm", "points"])] = 1
        elif op < 0.95:
            value = container[key]
            for _ in range(rng.choice((1, 10, 61, 62, 63, 64, 70))):
                value = [value]
            container[key] = value
        elif isinstance(container, list):
            container.append(rng.choice(BAD_VALUES))
    return tree


def encode(tree, encoding: str) -> bytes:
    if encoding == JSON:
        return json.dumps(tree, default=lambda b: b.hex()).encode()
    return msgpack.packb(tree, use_bin_type=True)


def mutate_bytes(data: bytes, rng: random.Random) -> bytes:
    data = bytearray(data)
    for _ in range(rng.choice((1, 1, 2, 4))):
        op = rng.random()
        at = rng.randrange(len(data)) if data else 0
        if op < 0.35 and data:
            data[at] = rng.randrange(256)
        elif op < 0.55:
            data[at:at] = bytes([rng.randrange(256)])
        elif op < 0.7 and data:
            del data[at : at + rng.randrange(1, 8)]
        elif op < 0.8:
            data = data[: rng.randrange(len(data) + 1)]
        elif data:
            run = data[at : at + rng.randrange(1, 16)]
            data[at:at] = run * rng.randrange(1, 4)
    return bytes(data)


def first_error_cpp(data: bytes, encoding: str):
    try:
        return None, _core.parse_scene_bytes(data, encoding)
    except _core.SceneError as error:
        return str(error), None


def first_error_python(data: bytes, encoding: str):
    try:
        return None, parse_scene(data, encoding)
    except SceneError as error:
        return str(error), None


def same_scene(cpp: dict, python) -> bool:
    metadata = cpp.pop("metadata")
    if scene_from_dict({**cpp, "metadata": python.metadata}) != python:
        return False
    # nlohmann writes NaN in free-form metadata as null; everything else must match exactly.
    text = json.dumps(python.metadata, default=str)
    return "NaN" in text or "Infinity" in text or metadata == json.loads(text)


@pytest.mark.parametrize("encoding", [JSON, MSGPACK])
@pytest.mark.parametrize("seed_index", [0, 1])
def test_both_readers_agree_on_mutated_files(encoding, seed_index):
    rng = random.Random(1000 * seed_index + (encoding == MSGPACK))
    seed = seeds()[seed_index]
    disagreements = []
    outcomes = {"accepted": 0, "rejected": 0}
    for i in range(COUNT):
        tree_level = i % 2 == 0
        if tree_level:
            data = encode(mutate_tree(seed, rng), encoding)
        else:
            data = mutate_bytes(encode(seed, encoding), rng)
        cpp_error, cpp_scene = first_error_cpp(data, encoding)
        python_error, python_scene = first_error_python(data, encoding)
        if cpp_error != python_error:
            disagreements.append((data[:200], cpp_error, python_error))
        elif cpp_error is None and not same_scene(cpp_scene, python_scene):
            disagreements.append((data[:200], "scene differs", ""))
        outcomes["rejected" if cpp_error else "accepted"] += 1
    assert not disagreements, f"{len(disagreements)} of {COUNT} differ; first: {disagreements[:3]}"
    # The mutations must exercise both outcomes, or the comparison proves little.
    assert outcomes["rejected"] > COUNT // 4 and outcomes["accepted"] > 0, outcomes


def test_the_vertices_of_an_accepted_mutation_are_the_same_arrays():
    data = encode(seeds()[1], MSGPACK)
    _, cpp = first_error_cpp(data, MSGPACK)
    _, python = first_error_python(data, MSGPACK)
    assert np.array_equal(cpp["vertices"], python.vertices)
    assert np.array_equal(cpp["tets"], python.tets)
