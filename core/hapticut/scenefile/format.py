"""Scene files, format version 1: reading, checking and atomic writing (docs/scene-format.md).

Two encodings of one tree: JSON (``*.hapticut.json``) and MessagePack (``*.hapticut.msgpack``,
for big meshes), chosen from the file name. The reader and the writer are the C++ ones
(core/src/scene_reader.cpp, scene_writer.cpp, called through hapticut._core), so the servo and
Python read every file the same way; this module adds only the Python Scene model and the
atomic write. Every problem raises SceneError whose message starts with the JSON pointer of the
offending field.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

import numpy as np

from hapticut import _core

from ..atomic_file import write_atomically
from .model import Material, Scene, SceneError, scene_from_dict, scene_to_dict

JSON = "json"
MSGPACK = "msgpack"
SCHEMA_PATH = Path(__file__).resolve().parent.parent / "schema" / "scene-v1.schema.json"

_log = logging.getLogger(__name__)


def encoding_for_path(path: str | os.PathLike) -> str:
    """MSGPACK for a name ending in ".msgpack", else JSON."""
    return MSGPACK if os.fspath(path).endswith(".msgpack") else JSON


def parse_scene(data: bytes, encoding: str = JSON, *, strict: bool = False) -> Scene:
    """The scene in ``data``; strict also rejects inverted tets instead of re-orienting them."""
    try:
        as_dict, reoriented = _core.parse_scene_document(bytes(data), _checked(encoding), strict)
    except _core.SceneError as error:
        raise SceneError(error.field, error.reason) from None
    if reoriented:
        _log.info("re-oriented %d inverted tets (swapped their last two vertices)", reoriented)
    return scene_from_dict(as_dict)


def serialize_scene(scene: Scene, encoding: str = JSON) -> bytes:
    """The file's bytes; raises SceneError (naming the field as in the file) for a bad scene."""
    try:
        return _core.serialize_scene_bytes(scene_to_dict(scene), _checked(encoding))
    except _core.SceneError as error:
        raise SceneError(error.field, error.reason) from None


def materials_problem(materials: list[Material]) -> SceneError | None:
    """The first problem the scene reader finds in this material table (a parameter out of
    range, a repeated name, a cut_to naming no material, naming a rigid one or making a
    cycle), as the SceneError a file of it would raise (``/materials/<i>/...``), or None.

    The writer's own checks, run on the table with a one-tet mesh of material 0: a builder
    finds what its scene file would be refused for before it meshes anything."""
    vertices, tets = _core.two_tets_mesh(10.0)
    probe = Scene(materials, vertices, tets[:1], np.zeros(1, np.int32))
    try:
        serialize_scene(probe)
    except SceneError as error:
        return error
    return None


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
