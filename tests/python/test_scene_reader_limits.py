"""The scene readers trust no input: each reproducer, through both readers.

Both readers decode with the C++ decoder (hapticut._core.decode_scene_tree, scene_tree.h), so
the bindings raise SceneError, never UnicodeDecodeError or RecursionError.
"""

from __future__ import annotations

import json
from pathlib import Path

import msgpack
import pytest
from hapticut import _core
from hapticut.scenefile import JSON, MSGPACK, SceneError, parse_scene

DATA = Path(__file__).resolve().parents[1] / "data"
EXAMPLE = (DATA / "two_tets.hapticut.json").read_bytes()
DEEP = "(root): nested deeper than 64 arrays and objects"


def both_errors(data: bytes, encoding: str) -> tuple[str, str]:
    """The C++ reader's and the Python reader's message for the same bytes."""
    with pytest.raises(_core.SceneError) as from_cpp:
        _core.parse_scene_bytes(data, encoding)
    with pytest.raises(SceneError) as from_python:
        parse_scene(data, encoding)
    return str(from_cpp.value), str(from_python.value)


def test_deep_json_is_a_scene_error_in_both_readers():
    assert both_errors(b"[" * 100000, JSON) == (DEEP, DEEP)


def test_deep_msgpack_is_a_scene_error_in_both_readers():
    assert both_errors(b"\x91" * 100000 + b"\xc0", MSGPACK) == (DEEP, DEEP)


def test_deep_metadata_is_a_scene_error_not_a_recursion_error():
    # On main the C++ reader accepted it and the binding raised RecursionError reading it back.
    deep = b'"metadata": {"deep": ' + b"[" * 2000 + b"1" + b"]" * 2000 + b", "
    text = EXAMPLE.replace(b'"metadata": {', deep, 1)
    assert both_errors(text, JSON) == (DEEP, DEEP)


def test_invalid_utf8_in_msgpack_is_a_scene_error_and_not_echoed():
    packed = bytearray(msgpack.packb(json.loads(EXAMPLE)))
    at = packed.index(b"\xa3air")
    packed[at + 1] = 0xFF
    expected = "/materials/0/name: invalid UTF-8 in a string"
    assert both_errors(bytes(packed), MSGPACK) == (expected, expected)
    text = EXAMPLE.replace(b'"air"', b'"\xffir"', 1)
    cpp, python = both_errors(text, JSON)
    assert cpp == python and cpp.startswith("(root): truncated or not valid JSON: ")
    assert cpp.isascii() and cpp.isprintable()


def test_duplicate_keys_are_rejected_not_last_wins():
    text = EXAMPLE.replace(
        b'"model": "drag", "drag_distance_mm": 1.0', b'"model": "rigid", "model": "free"'
    )
    expected = "/materials/1/model: duplicate key"
    assert both_errors(text, JSON) == (expected, expected)


def test_nothing_may_follow_the_value():
    expected = f"(root): truncated or not valid JSON: NUL byte at offset {len(EXAMPLE)}"
    assert both_errors(EXAMPLE + b"\x00garbage", JSON) == (expected, expected)
    cpp, python = both_errors(EXAMPLE + b"]", JSON)
    assert cpp == python and cpp.startswith("(root): truncated or not valid JSON: ")
    cpp, python = both_errors(msgpack.packb(json.loads(EXAMPLE)) + b"\xc0", MSGPACK)
    assert cpp == python and cpp.startswith("(root): truncated or not valid MessagePack: ")


def test_an_object_with_many_keys_is_read_by_both():
    tree = json.loads(EXAMPLE)
    tree["metadata"] = {f"k{i}": i for i in range(100000)}
    data = json.dumps(tree).encode()
    scene = parse_scene(data, JSON)
    assert list(scene.metadata)[-1] == "k99999" and len(scene.metadata) == 100000
    assert len(_core.parse_scene_bytes(data, JSON)["metadata"]) == 100000


def test_non_finite_numbers_are_named_the_same_way_by_both():
    tree = json.loads(EXAMPLE)
    tree["mesh"]["vertices"][3][1] = float("nan")
    expected = "/mesh/vertices/3/1: not a finite number"
    assert both_errors(msgpack.packb(tree), MSGPACK) == (expected, expected)
    # JSON has no NaN: the literal Python's json module writes is not JSON for either reader.
    cpp, python = both_errors(json.dumps(tree).encode(), JSON)
    assert cpp == python and cpp.startswith("(root): truncated or not valid JSON: ")
