"""The scene reader on mutated files: no crash, a SceneError for every bad file (one reader,
in C++, which Python calls).

Seeded mutations of two valid scenes, in both encodings: byte edits (flip, insert, delete,
truncate, repeat a run) and tree edits (replace a value with one of many bad values, drop a key,
add a key, nest deeper). Every file is read through hapticut.scenefile: it is rejected with a
SceneError naming a field, or accepted as a scene that writes and reads back the same.
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
from hapticut.scenefile import (
    JSON,
    MSGPACK,
    SceneError,
    parse_scene,
    scene_from_dict,
    serialize_scene,
)

DATA = Path(__file__).resolve().parents[1] / "data"
COUNT = int(os.environ.get("HAPTICUT_MUTATIONS", "750"))

BAD_VALUES = [
    None, True, False, 0, -1, 1, 2, 3, 2.5, -0.5, 1e-300, 1e6, 1e9, 1e20, 1e308, 2**31, 2**63,
    2**64 - 1, -(2**63), math.nan, math.inf, -math.inf, "", "x", "free", "rigid", "drag", "1",
    "independent", "locked", "Rigid",
    [], [0], [0, 1], [0, 1, 2], [0, 1, 2, 3], [[0, 0, 0]], {}, {"a": 1}, b"\x00\xff",
]  # fmt: skip


def seeds() -> list[dict]:
    example = json.loads((DATA / "two_tets.hapticut.json").read_text())
    viscous = json.loads(json.dumps(example))
    viscous["materials"].append({"name": "fat", "model": "viscous", "viscosity_N_s_per_mm": 0.002})
    viscous["materials"].append({"name": "skin", "model": "membrane", "break_force_N": 1.5})
    viscous["mesh"]["tet_materials"] = [2, 3]
    viscous["safety"] = {"max_force_N": 5.0, "max_transitions_per_tick": 64, "ramp_time_s": 0.5}
    viscous["blades"][0].update(coupling="independent", orientation="locked")
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
            key = rng.choice(["extra", "model", "name", "tolerance_mm", "points", "coupling"])
            container[key] = 1
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


def read(data: bytes, encoding: str):
    """(message, None) for a rejected file, (None, scene) for an accepted one; any other
    exception (a crash of the reader or of the conversion to Python) fails the test."""
    try:
        return None, parse_scene(data, encoding)
    except SceneError as error:
        return str(error), None


def well_formed(error: str) -> bool:
    """ "<field>: <reason>" with the field a JSON pointer, "(root)" or "(file)"."""
    field, separator, reason = error.partition(": ")
    return bool(separator and reason) and (field.startswith("/") or field == "(root)")


def reads_back(scene) -> bool:
    return (
        bool(np.isfinite(scene.vertices).all()) and read(serialize_scene(scene), JSON)[1] == scene
    )


@pytest.mark.parametrize("encoding", [JSON, MSGPACK])
@pytest.mark.parametrize("seed_index", [0, 1])
def test_the_reader_rejects_every_bad_mutation_with_a_scene_error(encoding, seed_index):
    rng = random.Random(1000 * seed_index + (encoding == MSGPACK))
    seed = seeds()[seed_index]
    problems = []
    outcomes = {"accepted": 0, "rejected": 0}
    for i in range(COUNT):
        tree_level = i % 2 == 0
        if tree_level:
            data = encode(mutate_tree(seed, rng), encoding)
        else:
            data = mutate_bytes(encode(seed, encoding), rng)
        error, scene = read(data, encoding)
        if error is not None:
            if not well_formed(error):
                problems.append((data[:200], error))
        elif not reads_back(scene):
            problems.append((data[:200], "accepted, but does not write and read back the same"))
        outcomes["rejected" if error else "accepted"] += 1
    assert not problems, f"{len(problems)} of {COUNT} wrong; first: {problems[:3]}"
    # The mutations must exercise both outcomes, or the test proves little.
    assert outcomes["rejected"] > COUNT // 4 and outcomes["accepted"] > 0, outcomes


def test_an_accepted_file_has_the_arrays_the_core_reads():
    data = encode(seeds()[1], MSGPACK)
    _, scene = read(data, MSGPACK)
    from_core = _core.parse_scene_bytes(data, MSGPACK)
    assert np.array_equal(from_core["vertices"], scene.vertices)
    assert np.array_equal(from_core["tets"], scene.tets)
    assert scene_from_dict(from_core) == scene
