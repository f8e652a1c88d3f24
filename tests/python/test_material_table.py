"""The one material table (C++) as Python, the CLI and the JSON Schema see it."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from hapticut import _core
from hapticut.commands.mesh import parse_material
from hapticut.cut_surface import CUTTABLE_MODELS
from hapticut.scenefile import SCHEMA_PATH, Material, materials_problem
from hapticut.scenefile.model import MODEL_PARAMETERS, PARAMETER_RANGES, SETTING_RANGES

TABLE = _core.material_table()
SCHEMA = json.loads(SCHEMA_PATH.read_text())


def run_cli(*args):
    return subprocess.run(
        [sys.executable, "-m", "hapticut.cli", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_materials_json_prints_the_table():
    result = run_cli("materials", "--json")
    assert result.returncode == 0, result.stderr
    printed = json.loads(result.stdout)
    # The engine's table, each model marked with whether a blade cuts it.
    cuttable = {m["name"]: m.pop("cuttable") for m in printed["models"]}
    assert printed == TABLE
    assert cuttable == {name: name in CUTTABLE_MODELS for name in MODEL_PARAMETERS}
    assert printed["version"] == 1
    assert [m["name"] for m in printed["models"]] == [
        "free", "drag", "rigid", "viscous", "membrane"
    ]  # fmt: skip
    drag = printed["models"][1]["parameters"][0]
    assert set(drag) >= {"name", "unit", "minimum", "maximum", "default", "summary"}
    assert (drag["name"], drag["unit"], drag["minimum"]) == ("drag_distance_mm", "mm", 0.0)
    presets = {p["name"]: p for p in printed["presets"]}
    assert list(presets) == ["air", "soft_tissue", "fat", "skin", "bone"]
    assert presets["soft_tissue"] == {
        "name": "soft_tissue",
        "label": "Soft tissue",
        "model": "drag",
        "parameters": {"drag_distance_mm": 2.0},
    }
    assert [presets[n]["model"] for n in presets] == [
        "free",
        "drag",
        "viscous",
        "membrane",
        "rigid",
    ]


def test_materials_prints_a_human_table():
    result = run_cli("materials")
    assert result.returncode == 0, result.stderr
    assert "drag_distance_mm" in result.stdout and "(0, 1000] mm" in result.stdout
    assert "soft_tissue" in result.stdout and "Soft tissue" in result.stdout


def test_every_range_is_finite_non_negative_and_holds_its_default():
    rows = [p for m in TABLE["models"] for p in m["parameters"]] + list(SETTING_RANGES.values())
    for row in rows:
        assert math.isfinite(row["minimum"]) and math.isfinite(row["maximum"]), row
        assert 0.0 <= row["minimum"] < row["maximum"], row
        low_ok = row["default"] > row["minimum"] or (
            not row["minimum_exclusive"] and row["default"] == row["minimum"]
        )
        assert low_ok and row["default"] <= row["maximum"], row


def test_the_cuttable_models_are_those_the_scene_reader_lets_take_a_cut_to():
    air = Material("air", "free")
    for model, takes in MODEL_PARAMETERS.items():
        required = {k: PARAMETER_RANGES[k]["default"] for k, needed in takes.items() if needed}
        problem = materials_problem([air, Material("m", model, cut_to="air", **required)])
        assert (problem is None) == (model in CUTTABLE_MODELS), (model, problem)
        if problem is not None:
            assert problem.field == "/materials/1/cut_to", problem


def test_presets_build_a_space():
    vertices, tets = _core.two_tets_mesh(10.0)
    for preset in TABLE["presets"]:
        material = {"name": preset["name"], "model": preset["model"], **preset["parameters"]}
        space = _core.Space(vertices, tets, np.zeros(2, np.int32), [material])
        assert space.material_names == [preset["name"]]


def _schema_bounds(prop: dict) -> tuple[float, bool, float]:
    if "exclusiveMinimum" in prop:
        return prop["exclusiveMinimum"], True, prop["maximum"]
    return prop["minimum"], False, prop["maximum"]


def test_schema_material_parameters_agree_with_the_table():
    material = SCHEMA["$defs"]["material"]
    assert material["properties"]["model"]["enum"] == [m["name"] for m in TABLE["models"]]
    parameter_properties = set(material["properties"]) - {"name", "model", "cut_to"}
    assert parameter_properties == set(PARAMETER_RANGES)
    for name, row in PARAMETER_RANGES.items():
        prop = material["properties"][name]
        assert prop["type"] == "number"
        assert _schema_bounds(prop) == (row["minimum"], row["minimum_exclusive"], row["maximum"])
        if not row["required"]:
            assert prop["default"] == row["default"], name
    rules = {rule["if"]["properties"]["model"]["const"]: rule["then"] for rule in material["allOf"]}
    assert set(rules) == set(MODEL_PARAMETERS)
    for model, takes in MODEL_PARAMETERS.items():
        then = rules[model]
        assert sorted(then.get("required", [])) == sorted(k for k, req in takes.items() if req)
        forbidden = {k for k, v in then.get("properties", {}).items() if v is False}
        # cut_to: only the cuttable models (drag, viscous, membrane) take one.
        assert forbidden - {"cut_to"} == set(PARAMETER_RANGES) - set(takes), model
        assert ("cut_to" in forbidden) == (model in ("free", "rigid")), model


def test_schema_settings_agree_with_the_engine_ranges():
    props = SCHEMA["properties"]
    where = {
        "stiffness_N_per_mm": props["coupling"]["properties"],
        "servo_rate_Hz": props["coupling"]["properties"],
        "tolerance_mm": props,
        **{k: props["safety"]["properties"] for k in props["safety"]["properties"]},
    }
    assert set(where) == set(SETTING_RANGES)
    for name, row in SETTING_RANGES.items():
        prop = where[name][name]
        assert _schema_bounds(prop) == (row["minimum"], row["minimum_exclusive"], row["maximum"])
        assert prop["default"] == row["default"], name


def test_mesh_material_rejects_a_parameter_of_another_model():
    # On main this was silently dropped: flesh became drag with drag_distance_mm=1.
    with pytest.raises(ValueError, match="break_force_N is not a parameter of model 'drag'"):
        parse_material("flesh=drag,break_force_N=2")
    with pytest.raises(ValueError, match="max_lag_mm is not a parameter of model 'rigid'"):
        parse_material("bone=rigid,max_lag_mm=3")
    with pytest.raises(ValueError, match=r"drag_distance_mm must be <= 1000, got 5000\.0"):
        parse_material("flesh=drag,drag_distance_mm=5000")
    with pytest.raises(ValueError, match="drag_distance_mm not a finite number"):
        parse_material("flesh=drag,drag_distance_mm=nan")
    # Defaults come from the table.
    default = PARAMETER_RANGES["viscosity_N_s_per_mm"]["default"]
    assert parse_material("goo=viscous")[1] == Material(
        "goo", "viscous", viscosity_N_s_per_mm=default
    )


def test_mesh_command_reports_the_other_models_parameter(tmp_path):
    result = run_cli(
        "mesh", tmp_path / "flesh.obj", "--material", "flesh=drag,break_force_N=2",
        "-o", tmp_path / "x.hapticut.json",
    )  # fmt: skip
    assert result.returncode == 2
    assert "break_force_N is not a parameter of model 'drag'" in result.stderr
