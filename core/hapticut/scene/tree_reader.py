"""Checks a decoded scene tree (format version 1) and builds the in-memory Scene.

Section by section the twin of read_tree() in core/src/scene_io.cpp: the same fields in the same
order with the same wording, so both languages report the same first error. Known fields are
checked in document order, then unknown fields are rejected.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import mesh_checks
from .model import (
    FORMAT_NAME,
    FORMAT_VERSION,
    MATERIAL_MODELS,
    MATERIAL_PARAMETERS,
    MODEL_PARAMETERS,
    PARAMETER_RANGES,
    SETTING_RANGES,
    UNITS,
    BladeSpec,
    Material,
    Safety,
    Scene,
)
from .tree_values import (
    ROOT,
    NameRegistry,
    child,
    dump_number,
    expect_array,
    expect_exact_string,
    expect_object,
    fail,
    read_in_range,
    read_int_between,
    read_int_in_range,
    read_integer,
    read_name,
    read_point,
    read_string,
    reject_unknown_fields,
    required,
)

MAX_INT32 = 2**31 - 1
ROOT_FIELDS = (
    "format",
    "version",
    "units",
    "coupling",
    "tolerance_mm",
    "safety",
    "materials",
    "mesh",
    "blades",
    "metadata",
)


def read_tree(root: Any, strict: bool = False) -> tuple[Scene, int]:
    """The scene, and how many inverted tets were re-oriented (always 0 when strict)."""
    expect_object(root, ROOT)
    _read_header(root)
    _read_units(root)
    coupling = _read_coupling(root)
    tolerance_mm = (
        read_in_range(root["tolerance_mm"], "/tolerance_mm", SETTING_RANGES["tolerance_mm"])
        if "tolerance_mm" in root
        else 0.0
    )
    safety = _read_safety(root)
    materials = _read_materials(root)
    vertices, tets, tet_materials, reoriented = _read_mesh(root, len(materials), strict)
    blades = _read_blades(root)
    metadata = root.get("metadata", {})
    expect_object(metadata, "/metadata")
    reject_unknown_fields(root, ROOT, ROOT_FIELDS)
    scene = Scene(
        materials=materials,
        vertices=vertices,
        tets=tets,
        tet_materials=tet_materials,
        blades=blades,
        tolerance_mm=tolerance_mm,
        safety=safety,
        metadata=metadata,
        **coupling,
    )
    return scene, reoriented


def _read_header(root: dict) -> None:
    expect_exact_string(required(root, ROOT, "format"), "/format", FORMAT_NAME)
    version = required(root, ROOT, "version")
    if read_integer(version, "/version") != FORMAT_VERSION:
        fail(
            "/version",
            f"unsupported format version {dump_number(version)} "
            f"(this build reads {FORMAT_VERSION})",
        )


def _read_units(root: dict) -> None:
    units = expect_object(required(root, ROOT, "units"), "/units")
    for key, unit in UNITS.items():
        expect_exact_string(required(units, "/units", key), child("/units", key), unit)
    reject_unknown_fields(units, "/units", UNITS)


def _read_coupling(root: dict) -> dict[str, float]:
    if "coupling" not in root:
        return {}
    coupling = expect_object(root["coupling"], "/coupling")
    known = ("stiffness_N_per_mm", "servo_rate_Hz")
    out = {
        key: read_in_range(coupling[key], child("/coupling", key), SETTING_RANGES[key])
        for key in known
        if key in coupling
    }
    reject_unknown_fields(coupling, "/coupling", known)
    return out


def _read_safety(root: dict) -> Safety:
    if "safety" not in root:
        return Safety()
    safety = expect_object(root["safety"], "/safety")
    readers = {
        "max_force_N": read_in_range,
        "max_torque_N_mm": read_in_range,
        "ramp_time_s": read_in_range,
        "max_transitions_per_tick": read_int_in_range,
        "capped_tick_force_N": read_in_range,
    }
    values = {
        key: read(safety[key], child("/safety", key), SETTING_RANGES[key])
        for key, read in readers.items()
        if key in safety
    }
    reject_unknown_fields(safety, "/safety", readers)
    return Safety(**values)


def _read_material(item: Any, pointer: str, names: NameRegistry) -> Material:
    expect_object(item, pointer)
    name_pointer = child(pointer, "name")
    name = read_name(required(item, pointer, "name"), name_pointer)
    names.add(name, name_pointer, pointer)
    model_pointer = child(pointer, "model")
    model = read_string(required(item, pointer, "model"), model_pointer)
    if model not in MATERIAL_MODELS:
        fail(model_pointer, f"unknown model '{model}' (expected {', '.join(MATERIAL_MODELS)})")
    takes = MODEL_PARAMETERS[model]
    parameters = {}
    for key in MATERIAL_PARAMETERS:
        parameter_pointer = child(pointer, key)
        if key not in takes:
            if key in item:
                fail(parameter_pointer, f"not a parameter of model '{model}'")
        elif key in item:
            parameters[key] = read_in_range(item[key], parameter_pointer, PARAMETER_RANGES[key])
        elif takes[key]:
            fail(parameter_pointer, "required field missing")
    reject_unknown_fields(item, pointer, ("name", "model", *MATERIAL_PARAMETERS))
    return Material(name=name, model=model, **parameters)


def _read_materials(root: dict) -> list[Material]:
    materials = expect_array(required(root, ROOT, "materials"), "/materials")
    if not materials:
        fail("/materials", "empty (a scene needs at least one material)")
    names = NameRegistry()
    return [_read_material(item, child("/materials", i), names) for i, item in enumerate(materials)]


def _read_mesh(
    root: dict, material_count: int, strict: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    mesh = expect_object(required(root, ROOT, "mesh"), "/mesh")
    vertices = mesh_checks.read_vertices(required(mesh, "/mesh", "vertices"), "/mesh/vertices")
    tets = mesh_checks.read_tet_indices(
        required(mesh, "/mesh", "tets"), "/mesh/tets", len(vertices)
    )
    mesh_checks.check_distinct_vertices(tets, "/mesh/tets")
    tets, reoriented = mesh_checks.check_volumes(vertices, tets, "/mesh/tets", strict)
    tet_materials = mesh_checks.read_tet_materials(
        required(mesh, "/mesh", "tet_materials"), "/mesh/tet_materials", len(tets), material_count
    )
    reject_unknown_fields(mesh, "/mesh", ("vertices", "tets", "tet_materials"))
    return vertices, tets.astype(np.int32), tet_materials.astype(np.int32), reoriented


def _read_blade(item: Any, pointer: str, names: NameRegistry) -> BladeSpec:
    expect_object(item, pointer)
    name_pointer = child(pointer, "name")
    name = read_name(required(item, pointer, "name"), name_pointer)
    names.add(name, name_pointer, pointer)
    start = read_point(required(item, pointer, "start_mm"), child(pointer, "start_mm"))
    end = read_point(required(item, pointer, "end_mm"), child(pointer, "end_mm"))
    points = 50
    if "points" in item:
        points = read_int_between(item["points"], child(pointer, "points"), 1, MAX_INT32)
    reject_unknown_fields(item, pointer, ("name", "start_mm", "end_mm", "points"))
    return BladeSpec(name=name, start_mm=start, end_mm=end, points=points)


def _read_blades(root: dict) -> list[BladeSpec]:
    if "blades" not in root:
        return []
    blades = expect_array(root["blades"], "/blades")
    names = NameRegistry()
    return [_read_blade(item, child("/blades", i), names) for i, item in enumerate(blades)]
