"""The scene file, format version 1: the in-memory Scene (model.py) and reading and writing it
(format.py, through the one C++ reader and writer). Building scenes is hapticut.scenebuild."""

from .format import (
    JSON,
    MSGPACK,
    SCHEMA_PATH,
    encoding_for_path,
    load_scene,
    materials_problem,
    parse_scene,
    save_scene,
    serialize_scene,
)
from .model import (
    BLADE_COUPLINGS,
    BLADE_ORIENTATIONS,
    FORMAT_NAME,
    FORMAT_VERSION,
    MATERIAL_MODELS,
    BladeSpec,
    Material,
    Safety,
    Scene,
    SceneError,
    parameter_problem,
    scene_from_dict,
    scene_to_dict,
)

__all__ = [
    "BLADE_COUPLINGS",
    "BLADE_ORIENTATIONS",
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
    "materials_problem",
    "parameter_problem",
    "parse_scene",
    "save_scene",
    "scene_from_dict",
    "scene_to_dict",
    "serialize_scene",
]
