"""Scene files, format version 1: reading, checking and atomic writing (docs/scene-format.md).

Two encodings of one tree: JSON (``*.hapticut.json``) and MessagePack (``*.hapticut.msgpack``,
for big meshes), chosen from the file name. Every problem raises SceneError whose message starts
with the JSON pointer of the offending field; core/src/scene_io.cpp reads and writes the same
files with the same checks and wording.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

from hapticut import _core

from ..atomic_file import write_atomically
from .model import (
    FORMAT_NAME,
    FORMAT_VERSION,
    MATERIAL_MODELS,
    BladeSpec,
    Material,
    Safety,
    Scene,
    SceneError,
    scene_from_dict,
    scene_to_dict,
)
from .tree_reader import read_tree
from .tree_writer import encode_json, encode_msgpack, scene_to_tree

__all__ = [
    "FORMAT_NAME",
    "FORMAT_VERSION",
    "JSON",
    "MATERIAL_MODELS",
    "MSGPACK",
    "SCHEMA_PATH",
    "BladeSpec",
    "Material",
    "Safety",
    "Scene",
    "SceneError",
    "encoding_for_path",
    "load_scene",
    "parse_scene",
    "save_scene",
    "scene_from_dict",
    "scene_to_dict",
    "serialize_scene",
]

JSON = "json"
MSGPACK = "msgpack"
SCHEMA_PATH = Path(__file__).resolve().parent.parent / "schema" / "scene-v1.schema.json"

_log = logging.getLogger(__name__)


def encoding_for_path(path: str | os.PathLike) -> str:
    """MSGPACK for a name ending in ".msgpack", else JSON."""
    return MSGPACK if os.fspath(path).endswith(".msgpack") else JSON


def parse_scene(data: bytes, encoding: str = JSON, *, strict: bool = False) -> Scene:
    """The scene in ``data``; strict also rejects inverted tets instead of re-orienting them."""
    scene, reoriented = read_tree(_decode(data, encoding), strict=strict)
    if reoriented:
        _log.info("re-oriented %d inverted tets (swapped their last two vertices)", reoriented)
    return scene


def serialize_scene(scene: Scene, encoding: str = JSON) -> bytes:
    """The file's bytes; raises SceneError (naming the field as in the file) for a bad scene."""
    tree = scene_to_tree(scene)
    read_tree(tree)  # Never write what the reader would reject.
    try:
        return encode_json(tree) if _checked(encoding) == JSON else encode_msgpack(tree)
    except (TypeError, ValueError) as error:  # Only "metadata" can hold such values.
        raise SceneError("/metadata", f"cannot encode: {error}") from None


def load_scene(path: str | os.PathLike, *, strict: bool = False) -> Scene:
    """Read a scene file (file-system errors raise OSError, as open() does)."""
    with open(path, "rb") as file:
        data = file.read()
    return parse_scene(data, encoding_for_path(path), strict=strict)


def save_scene(scene: Scene, path: str | os.PathLike) -> None:
    """Write atomically: a temporary file beside ``path``, flushed, then renamed over it."""
    write_atomically(path, serialize_scene(scene, encoding_for_path(path)))


def _checked(encoding: str) -> str:
    if encoding not in (JSON, MSGPACK):
        raise ValueError(f"unknown encoding {encoding!r} (expected {JSON!r} or {MSGPACK!r})")
    return encoding


def _decode(data: bytes, encoding: str):
    """The tree in ``data``, decoded by the C++ decoder the C++ reader uses too (scene_tree.h):
    nesting bounded, duplicate keys, invalid UTF-8, NUL bytes and trailing bytes rejected, so
    both readers see every file the same way."""
    try:
        return _core.decode_scene_tree(bytes(data), _checked(encoding))
    except _core.SceneError as error:
        raise SceneError(error.field, error.reason) from None
