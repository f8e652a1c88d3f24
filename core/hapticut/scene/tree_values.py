"""Checks of single values in a decoded scene tree, each failing with a SceneError that names
the field by its JSON pointer. Same rules and wording as the helpers in core/src/scene_io.cpp.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from typing import Any, NoReturn

from msgpack import ExtType

from .model import SceneError

ROOT = ""  # The JSON pointer of the whole document, shown as "(root)".
ARRAY_TYPES = (list, tuple)


def child(pointer: str, key: str | int) -> str:
    """The pointer of member ``key`` (RFC 6901: "~" -> "~0", "/" -> "~1")."""
    if isinstance(key, int):
        return f"{pointer}/{key}"
    return pointer + "/" + key.replace("~", "~0").replace("/", "~1")


def fail(pointer: str, reason: str) -> NoReturn:
    raise SceneError(pointer or "(root)", reason)


def kind_of(value: Any) -> str:
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int | float):
        return "number"
    if isinstance(value, str):
        return "string"
    if isinstance(value, dict):
        return "object"
    if isinstance(value, ARRAY_TYPES):
        return "array"
    if value is None:
        return "null"
    if isinstance(value, bytes | bytearray | memoryview | ExtType):
        return "binary"  # MessagePack bin and ext values.
    return type(value).__name__


def dump_number(value: int | float) -> str:
    """A number as the C++ reader prints it (nlohmann's dump and Python's repr agree)."""
    return json.dumps(value)


def is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def required(obj: dict, pointer: str, key: str) -> Any:
    if key not in obj:
        fail(child(pointer, key), "required field missing")
    return obj[key]


def expect_object(value: Any, pointer: str) -> dict:
    if not isinstance(value, dict):
        fail(pointer, f"expected an object, got {kind_of(value)}")
    return value


def expect_array(value: Any, pointer: str) -> list:
    if not isinstance(value, ARRAY_TYPES):
        fail(pointer, f"expected an array, got {kind_of(value)}")
    return value


def read_string(value: Any, pointer: str) -> str:
    if not isinstance(value, str):
        fail(pointer, f"expected a string, got {kind_of(value)}")
    return value


def read_name(value: Any, pointer: str) -> str:
    name = read_string(value, pointer)
    if not name:
        fail(pointer, "must not be empty")
    return name


def expect_exact_string(value: Any, pointer: str, expected: str) -> None:
    text = read_string(value, pointer)
    if text != expected:
        fail(pointer, f"expected '{expected}', got '{text}'")


def read_finite(value: Any, pointer: str) -> float:
    if not is_number(value):
        fail(pointer, f"expected a number, got {kind_of(value)}")
    try:
        number = float(value)
    except OverflowError:  # An integer beyond the double range.
        number = math.inf
    if not math.isfinite(number):
        fail(pointer, "not a finite number")
    return number


def read_in_range(value: Any, pointer: str, limits: dict[str, Any]) -> float:
    """A number in the engine's range for it (a row of SETTING_RANGES or PARAMETER_RANGES)."""
    number = read_finite(value, pointer)
    low = limits["minimum"]
    if not (number > low if limits["minimum_exclusive"] else number >= low):
        relation = ">" if limits["minimum_exclusive"] else ">="
        fail(pointer, f"must be {relation} {low:g}, got {dump_number(value)}")
    if not number <= limits["maximum"]:
        fail(pointer, f"must be <= {limits['maximum']:g}, got {dump_number(value)}")
    return number


def read_integer(value: Any, pointer: str) -> int:
    """An integer as JSON Schema sees it: 3 and 3.0 both count."""
    if isinstance(value, int) and not isinstance(value, bool):
        return value
    if not is_number(value):
        fail(pointer, f"expected an integer, got {kind_of(value)}")
    if not (math.isfinite(value) and value.is_integer()):
        fail(pointer, "expected an integer, got a non-integer number")
    return int(value)


def read_int_between(value: Any, pointer: str, low: int, high: int) -> int:
    number = read_integer(value, pointer)
    if number < low:
        fail(pointer, f"must be >= {low}, got {dump_number(value)}")
    if number > high:
        fail(pointer, f"must be <= {high}, got {dump_number(value)}")
    return number


def read_int_in_range(value: Any, pointer: str, limits: dict[str, Any]) -> int:
    return read_int_between(value, pointer, int(limits["minimum"]), int(limits["maximum"]))


def read_point(value: Any, pointer: str) -> tuple[float, float, float]:
    expect_array(value, pointer)
    if len(value) != 3:
        fail(pointer, f"expected 3 coordinates, got {len(value)}")
    x, y, z = (read_finite(value[k], child(pointer, k)) for k in range(3))
    return (x, y, z)


def reject_unknown_fields(obj: dict, pointer: str, known: Iterable[str]) -> None:
    """Checked after an object's known fields, so a misspelt optional field is reported."""
    known = set(known)
    for key in obj:
        if key not in known:
            fail(child(pointer, str(key)), "unknown field")


class NameRegistry:
    """Unique names: "/materials/3/name: duplicate name 'bone' (first at /materials/1)"."""

    def __init__(self) -> None:
        self._first: dict[str, str] = {}

    def add(self, name: str, name_pointer: str, item_pointer: str) -> None:
        first = self._first.setdefault(name, item_pointer)
        if first != item_pointer:
            fail(name_pointer, f"duplicate name '{name}' (first at {first})")
