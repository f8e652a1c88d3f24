"""Scene files across languages: what Python writes C++ reads, and the reverse, through the
bindings in core/python/bind_scene.cpp. Needs the built module hapticut._core."""

from __future__ import annotations

import json
import math

import msgpack
import numpy as np
import pytest
from hapticut import _core
from hapticut.scenefile import (
    JSON,
    MSGPACK,
    BladeSpec,
    Material,
    SceneError,
    load_scene,
    parse_scene,
    save_scene,
    scene_from_dict,
    scene_to_dict,
    serialize_scene,
)
from scene_test_support import ERROR_CASES, EXAMPLE_PATH, apply_patch, example_tree, grid_scene

ENCODINGS = [JSON, MSGPACK]
SUFFIX = {JSON: ".hapticut.json", MSGPACK: ".hapticut.msgpack"}


def rich_scene():
    """Every model, uneven doubles, blades and nested metadata."""
    scene = grid_scene(2)
    rng = np.random.default_rng(3)
    scene.vertices = scene.vertices + rng.uniform(-0.01, 0.01, scene.vertices.shape)
    scene.materials = [
        Material("air", "free"),
        Material("flesh", "drag", drag_distance_mm=1.0),
        Material("bone", "rigid"),
        Material("fluid", "viscous", viscosity_N_s_per_mm=0.001, max_lag_mm=7.5),
        Material("skin", "membrane", break_force_N=1.25),
    ]
    scene.tet_materials = (np.arange(len(scene.tets)) % 5).astype(np.int32)
    scene.blades = [
        BladeSpec("scalpel", (0.0, 0.0, 0.0), (100.0, 0.0, 0.0), 50),
        BladeSpec("needle", (0.1, 0.2, 0.3), (1e-7, -2e20, 1.0 / 3.0), 1, coupling="independent"),
        BladeSpec("chisel", (0.0, 0.0, 0.0), (0.0, 0.0, 20.0), 9, orientation="locked"),
    ]
    scene.stiffness_N_per_mm = 0.25
    scene.tolerance_mm = 1e-6
    scene.metadata = {"source": "test", "layers": [1, 2.5, None, True], "name": "Zoë"}
    return scene


def core_error(data: bytes, encoding: str, strict: bool = False) -> str:
    with pytest.raises(_core.SceneError) as caught:
        _core.parse_scene_bytes(data, encoding, strict)
    return str(caught.value)


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_python_writes_cpp_reads(tmp_path, encoding):
    scene = rich_scene()
    path = tmp_path / f"scene{SUFFIX[encoding]}"
    save_scene(scene, path)
    from_cpp = _core.read_scene_file(str(path))
    assert from_cpp["vertices"].dtype == np.float64 and from_cpp["vertices"].shape[1] == 3
    assert from_cpp["tets"].dtype == np.int32 and from_cpp["tet_materials"].dtype == np.int32
    assert scene_from_dict(from_cpp) == scene


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_cpp_writes_python_reads(tmp_path, encoding):
    scene = rich_scene()
    path = tmp_path / f"scene{SUFFIX[encoding]}"
    _core.write_scene_file(scene_to_dict(scene), str(path))
    assert load_scene(path) == scene
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # No temporary left behind.


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_blade_settings_cross_languages_and_reach_the_engine(tmp_path, encoding):
    """What a file says of a blade's coupling and orientation is what C++ reads, and the engine's
    blade (engine.make_blade) is built with it."""
    from hapticut import engine

    scene = rich_scene()
    path = tmp_path / f"scene{SUFFIX[encoding]}"
    save_scene(scene, path)
    from_cpp = _core.read_scene_file(str(path))
    settings = [(b["name"], b["coupling"], b["orientation"]) for b in from_cpp["blades"]]
    assert settings == [
        ("scalpel", "rigid", "free"),
        ("needle", "independent", "free"),
        ("chisel", "rigid", "locked"),
    ]
    space = engine.space_from_scene(scene)
    blades = [engine.make_blade(space, spec) for spec in load_scene(path).blades]
    assert [(b.coupling, b.orientation) for b in blades] == [s[1:] for s in settings]


def test_both_writers_write_the_same_json():
    for scene in (load_scene(EXAMPLE_PATH), rich_scene()):
        from_python = serialize_scene(scene, JSON)
        assert _core.serialize_scene_bytes(scene_to_dict(scene), JSON) == from_python


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_json_and_msgpack_across_languages(encoding):
    other = MSGPACK if encoding == JSON else JSON
    scene = rich_scene()
    via_cpp = _core.parse_scene_bytes(serialize_scene(scene, encoding), encoding)
    back = parse_scene(_core.serialize_scene_bytes(via_cpp, other), other)
    assert back == scene


@pytest.mark.parametrize("encoding", ENCODINGS)
@pytest.mark.parametrize("case", ERROR_CASES, ids=[case["name"] for case in ERROR_CASES])
def test_both_readers_give_the_same_error(case, encoding):
    tree = apply_patch(example_tree(), case["patch"])
    data = json.dumps(tree).encode() if encoding == JSON else msgpack.packb(tree)
    strict = case.get("strict", False)
    with pytest.raises(SceneError) as from_python:
        parse_scene(data, encoding, strict=strict)
    assert core_error(data, encoding, strict) == str(from_python.value) == case["error"]


def test_core_error_is_a_value_error_with_the_field():
    tree = apply_patch(example_tree(), [{"op": "replace", "path": "/version", "value": 2}])
    with pytest.raises(ValueError) as caught:
        _core.parse_scene_bytes(json.dumps(tree).encode(), JSON)
    assert isinstance(caught.value, _core.SceneError)
    assert caught.value.field == "/version"
    assert caught.value.reason == "unsupported format version 2 (this build reads 1)"


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_truncated_file(encoding):
    data = serialize_scene(load_scene(EXAMPLE_PATH), encoding)[:-7]
    name = "JSON" if encoding == JSON else "MessagePack"
    assert core_error(data, encoding).startswith(f"(root): truncated or not valid {name}: ")


def test_nan_written_by_python_is_rejected_by_both():
    tree = example_tree()
    tree["mesh"]["vertices"][3][1] = math.nan
    packed = msgpack.packb(tree)
    assert core_error(packed, MSGPACK) == "/mesh/vertices/3/1: not a finite number"
    # json.dumps writes a NaN literal, which is not JSON: both readers reject the text alike.
    text = json.dumps(tree).encode()
    assert core_error(text, JSON).startswith("(root): truncated or not valid JSON: ")
    with pytest.raises(SceneError) as from_python:
        parse_scene(text, JSON)
    assert str(from_python.value) == core_error(text, JSON)


def test_inverted_tet_both_ways():
    tree = example_tree()
    tree["mesh"]["tets"][1] = [2, 1, 3, 4]
    data = json.dumps(tree).encode()
    assert _core.parse_scene_bytes(data, JSON)["tets"].tolist() == parse_scene(data).tets.tolist()
    assert core_error(data, JSON, strict=True) == "/mesh/tets/1: inverted (negative volume)"


def test_read_scene_file_strict_and_missing_file(tmp_path):
    with pytest.raises(_core.SceneError) as caught:
        _core.read_scene_file(str(tmp_path / "absent.hapticut.json"))
    assert caught.value.field == "(file)"
    assert scene_from_dict(_core.read_scene_file(str(EXAMPLE_PATH), strict=True)) == load_scene(
        EXAMPLE_PATH
    )


def test_bad_scene_dict_is_rejected_by_the_cpp_writer(tmp_path):
    as_dict = scene_to_dict(load_scene(EXAMPLE_PATH))
    as_dict["vertices"] = as_dict["vertices"][:, :2]
    with pytest.raises(_core.SceneError, match=r"^/mesh/vertices: expected an array of shape"):
        _core.write_scene_file(as_dict, str(tmp_path / "bad.hapticut.json"))
    as_dict = scene_to_dict(load_scene(EXAMPLE_PATH))
    as_dict["tet_materials"] = np.array([1, 9])
    with pytest.raises(_core.SceneError, match=r"^/mesh/tet_materials/1: unknown material 9"):
        _core.write_scene_file(as_dict, str(tmp_path / "bad.hapticut.json"))
    # The transition budget where the file keeps it, not where the dict does: no value dropped.
    as_dict = scene_to_dict(load_scene(EXAMPLE_PATH))
    as_dict["safety"]["max_transitions_per_tick"] = as_dict.pop("max_transitions_per_tick")
    with pytest.raises(_core.SceneError, match=r"^/safety/max_transitions_per_tick: a scene dict"):
        _core.write_scene_file(as_dict, str(tmp_path / "bad.hapticut.json"))
    assert list(tmp_path.iterdir()) == []
